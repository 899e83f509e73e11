"""Iterative solvers of (I - diag(rho) F) B = E: Jacobi on the GPU, Jacobi and
Gauss-Seidel on the CPU (float64). All three share one stopping rule
(`Convergence`): stop when max |B^k - B^(k-1)| <= tolerance * max B; refuse
with a clear message when the iteration cap is hit, the change stalls above
the tolerance (precision floor) or grows (divergence).
"""

from __future__ import annotations

import numpy as np

from ..errors import SolveCancelled, SolveError
from ..gpu import GPU, storage, work_groups

GPU_CHECK_EVERY = 16  # sweeps between readbacks of the convergence pair
STALL_CHECKS = 40  # checks without a 1 % improvement before we call it stalled
GAUSS_SEIDEL_BLOCK = 64
# Gauss-Seidel sums F's rows in float32 (half the memory traffic of widening each block to float64,
# which is what a sweep costs) when the tolerance is at least this: float32 sums are off by ~1e-7 of B,
# a hundredth of such a tolerance; finer ones need float64
SINGLE_SUMS_TOLERANCE = 1e-5


class Convergence:
    """The one stopping rule of every linear solver; records the history for the report."""

    def __init__(self, name: str, tolerance: float, max_iterations: int, should_cancel=None, progress=None):
        self.name = name
        self.tolerance = tolerance
        self.max_iterations = max_iterations
        self.should_cancel = should_cancel
        self.progress = progress
        self.best = np.inf
        self.checks_since_best = 0
        self.first = None
        self.smallest_change = np.inf
        self.relative_change = np.inf
        self.iterations = 0

    def done(self, iterations: int, max_change: float, max_value: float) -> bool:
        """True when converged; raises SolveError when it never will."""
        self.iterations = iterations
        if not (np.isfinite(max_change) and np.isfinite(max_value)):
            raise SolveError(f"{self.name} diverged (non-finite radiosity after {iterations} iterations)")
        relative = max_change / max_value if max_value > 0 else 0.0
        self.relative_change = relative
        if self.first is None:
            self.first = relative
        if relative <= self.tolerance:
            return True
        if self.should_cancel is not None and self.should_cancel():
            raise SolveCancelled("cancelled")
        # a converging iteration shrinks its change geometrically; growth means divergence
        # (spectral radius of diag(rho) F above 1: unphysical reflectance or form factors)
        self.smallest_change = min(self.smallest_change, max_change)
        if relative > 1e3 * max(self.first, self.tolerance) or max_change > 10 * self.smallest_change > 0:
            raise SolveError(
                f"{self.name} diverged (the change grew to {max_change:.3g} after {iterations} iterations);"
                " check that reflectances are below 1"
            )
        if relative < 0.99 * self.best:
            self.best, self.checks_since_best = relative, 0
        else:
            self.checks_since_best += 1
            if self.checks_since_best >= STALL_CHECKS:
                raise SolveError(
                    f"{self.name} stalled at relative change {relative:.3g}, above the tolerance"
                    f" {self.tolerance:.3g} (precision floor); raise --tolerance or use --solver gauss-seidel"
                )
        if iterations >= self.max_iterations:
            raise SolveError(
                f"{self.name} did not converge in {iterations} iterations (relative change"
                f" {relative:.3g} > tolerance {self.tolerance:.3g}); raise --tolerance or the iteration cap"
            )
        if self.progress is not None:
            # progress in log space from the first change to the tolerance
            span = np.log(max(self.first, self.tolerance * 1.0001) / self.tolerance)
            fraction = 1 - np.log(max(relative, self.tolerance) / self.tolerance) / span
            self.progress(float(np.clip(fraction, 0, 1)), f"{self.name}: iteration {iterations}",
                          {"iterations": iterations, "relative_change": relative})
        return False


def widened_product(matrix: np.ndarray, vectors: np.ndarray, block: int = 512) -> np.ndarray:
    """matrix @ vectors with float64 sums for a float32 matrix, widening a block of rows at a
    time (a float64 copy of the whole matrix would double the memory the guard allowed)."""
    result = np.empty((len(matrix),) + vectors.shape[1:], dtype=np.float64)
    for start in range(0, len(matrix), block):
        result[start:start + block] = matrix[start:start + block] @ vectors
    return result


def jacobi_cpu(form_factors, reflectance, emission, monitor: Convergence) -> np.ndarray:
    matrix = np.asarray(form_factors, dtype=np.float64)
    radiosity = emission.astype(np.float64).copy()
    iteration = 0
    while True:
        updated = emission + reflectance * (matrix @ radiosity)
        iteration += 1
        change = np.abs(updated - radiosity).max()
        radiosity = updated
        if monitor.done(iteration, change, radiosity.max()):
            return radiosity


def gauss_seidel(form_factors, reflectance, emission, monitor: Convergence, block: int = GAUSS_SEIDEL_BLOCK):
    """Point Gauss-Seidel, computed a block of rows at a time: within a block the strictly
    lower part is solved exactly with precomputed inverses of (I - rho L), so the result
    is the same as row-by-row Gauss-Seidel without a Python loop over rows. The matrix stays
    in its own precision (float32 from the hemi-cubes: a float64 copy would double the memory the
    guard allowed); its rows are summed in float32 against a float32 copy of B where the tolerance
    allows it (SINGLE_SUMS_TOLERANCE), else each block of rows is widened as it is used and the
    sums are float64. The block's own part (L, the inverses) and B are float64 either way."""
    matrix = np.asarray(form_factors)
    single = matrix.dtype == np.float32 and monitor.tolerance >= SINGLE_SUMS_TOLERANCE
    count = len(matrix)
    starts = range(0, count, block)
    lowers, inverses = [], []
    for start in starts:
        stop = min(start + block, count)
        lower = np.tril(matrix[start:stop, start:stop].astype(np.float64), -1)
        # one inverse per channel: (3, b, b)
        system = np.eye(stop - start)[None] - reflectance[start:stop].T[:, :, None] * lower[None]
        lowers.append(lower)
        inverses.append(np.linalg.inv(system))
    radiosity = emission.astype(np.float64).copy()
    summed = radiosity.astype(np.float32) if single else radiosity  # what F's rows are summed against
    iteration = 0
    while True:
        previous = radiosity.copy()
        for start, lower, inverse in zip(starts, lowers, inverses):
            stop = start + len(lower)
            gathered = matrix[start:stop] @ summed - lower @ radiosity[start:stop]
            rhs = emission[start:stop] + reflectance[start:stop] * gathered
            radiosity[start:stop] = np.einsum("cij,jc->ic", inverse, rhs)
            if single:
                summed[start:stop] = radiosity[start:stop]
        iteration += 1
        if monitor.done(iteration, np.abs(radiosity - previous).max(), radiosity.max()):
            return radiosity


def _vec4(array: np.ndarray, rows: int) -> bytes:
    padded = np.zeros((rows, 4), dtype=np.float32)
    padded[: len(array), :3] = array
    return padded.tobytes()


def jacobi_gpu(gpu: GPU, form_factors, reflectance, emission, monitor: Convergence) -> np.ndarray:
    count = len(form_factors)
    shader = gpu.compute("jacobi_sweep.comp")
    with gpu.resources() as res:
        buffers = {
            "FORM_FACTORS": res.buffer(np.ascontiguousarray(form_factors, dtype=np.float32).tobytes()),
            "JACOBI_EMISSION": res.buffer(_vec4(emission, count)),
            "JACOBI_REFLECTANCE": res.buffer(_vec4(reflectance, count)),
            "CONVERGENCE": res.buffer(reserve=8),
        }
        for name, buffer in buffers.items():
            buffer.bind_to_storage_buffer(storage(name))
        old, new = res.buffer(_vec4(emission, count + 1)), res.buffer(_vec4(emission, count + 1))
        shader["patch_count"] = count
        iteration = 0
        while True:
            for sweep in range(GPU_CHECK_EVERY):
                old.bind_to_storage_buffer(storage("RADIOSITY_OLD"))
                new.bind_to_storage_buffer(storage("RADIOSITY_NEW"))
                if sweep == GPU_CHECK_EVERY - 1:  # the pair read back is the last sweep's
                    buffers["CONVERGENCE"].clear()
                shader.run(work_groups(count, 64))
                gpu.ctx.memory_barrier()
                old, new = new, old
                iteration += 1
            change, value = np.frombuffer(buffers["CONVERGENCE"].read(), dtype=np.float32)
            if monitor.done(iteration, float(change), float(value)):
                result = np.frombuffer(old.read(), dtype=np.float32).reshape(-1, 4)[:count, :3]
                return result.astype(np.float64)


def solve_linear(gpu: GPU, solver: str, form_factors, reflectance, emission, monitor: Convergence) -> np.ndarray:
    reflectance = np.asarray(reflectance, dtype=np.float64)
    emission = np.asarray(emission, dtype=np.float64)
    if solver == "jacobi-gpu":
        return jacobi_gpu(gpu, form_factors, reflectance, emission, monitor)
    if solver == "jacobi-cpu":
        return jacobi_cpu(form_factors, reflectance, emission, monitor)
    if solver == "gauss-seidel":
        return gauss_seidel(form_factors, reflectance, emission, monitor)
    raise SolveError(f"unknown solver '{solver}'")

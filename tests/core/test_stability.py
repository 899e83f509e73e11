"""Hard cases: results stay finite, non-negative, bounded against exact or independent references,
and energy-balanced — or the solve stops with a clear SolveError, never silently wrong.

Why each case is hard (also in the README, "Hard cases"):
- ρ → 1 in a closed box: the solution is E/(1 − ρ) (×100, ×1000); every error in a form-factor
  row sum and every residual change is amplified by ρ/(1 − ρ), iterations grow like 1/(1 − ρ),
  and fp32 sweeps hit their precision floor before a tight tolerance.
- Scale 1e-4 / 1e4 and emission × 1e6: absolute epsilons (near planes, "small" thresholds) break.
- 10 000 patches: a row sum of 10 000 fp32 terms of one sign accumulates rounding.
- Touching patches, grazing light, slivers: the kernel cos cos / (π r²) is near-singular or
  near zero; centre-point sampling and rasterization break down first there.
"""

import numpy as np
import pytest
from scenes import closed_cube, opposed_squares, perpendicular_squares, solve_settings, surface

from radiosity_addon.core.hemicube import linear_solvers
from radiosity_addon.core import point_to_polygon
from radiosity_addon.core import load_scene, scene_from_dict
from radiosity_addon.core import SolveError, SolveSettings
from radiosity_addon.core import solve

SOLVERS = ["jacobi-gpu", "jacobi-cpu", "gauss-seidel"]


def hemicube(**overrides) -> SolveSettings:
    """The full original method (no analytic shortcuts), small enough for tests."""
    settings = dict(method="hemicube", subdiv=2, hemicube_res=32, skip_unneeded=False)
    return solve_settings(**(settings | overrides))


def assert_physical(solution):
    radiosity = solution.patch_radiosity
    assert np.all(np.isfinite(radiosity)), "non-finite radiosity"
    assert np.all(radiosity >= 0), f"negative radiosity {radiosity.min()}"
    assert np.all(radiosity >= solution.patches.emission - 1e-9 * radiosity.max()), "B below E"


def energy_imbalance(solution) -> float:
    """Closed scene: emitted power Σ A E against absorbed power Σ A (1 − ρ) H, H = (B − E)/ρ."""
    patches, radiosity = solution.patches, solution.patch_radiosity
    area = patches.area[:, None]
    irradiance = (radiosity - patches.emission) / patches.reflectance
    emitted = (area * patches.emission).sum()
    absorbed = (area * (1 - patches.reflectance) * irradiance).sum()
    return abs(absorbed - emitted) / emitted


# --- reflectance near 1 --------------------------------------------------------------------------

@pytest.mark.parametrize("reflectance", [0.99, 0.999])
@pytest.mark.parametrize("solver", SOLVERS)
def test_closed_box_high_reflectance_converges_or_says_why(gpu, reflectance, solver):
    scene = scene_from_dict(closed_cube(reflectance=reflectance, emission=1.0))
    tolerance = 1e-6
    try:
        solution = solve(scene, hemicube(solver=solver, tolerance=tolerance), gpu=gpu)
    except SolveError as error:
        # the only acceptable failure: fp32 sweeps reaching their floor, said plainly with a remedy
        assert solver == "jacobi-gpu" and "precision floor" in str(error) and "--tolerance" in str(error)
        return
    assert_physical(solution)
    exact = 1.0 / (1 - reflectance)
    amplification = reflectance / (1 - reflectance)
    # the stopping rule leaves a geometric tail of about tolerance × ρ/(1 − ρ); F rows are sums of
    # fp32 fixed-point fractions (off 1 by ~1e-7), also amplified by ρ/(1 − ρ)
    bound = 2 * tolerance * amplification + 2e-7 * amplification
    np.testing.assert_allclose(solution.patch_radiosity, exact, rtol=bound)
    assert energy_imbalance(solution) < bound


def test_closed_box_analytic_kernel_bias_is_bounded(gpu):
    """With the scene analysis' analytic (centre-point) form factors, rows sum to slightly under 1,
    and the bias is ρ(1 − row sum)/(1 − ρ): bounded, never a blow-up."""
    reflectance = 0.99
    scene = scene_from_dict(closed_cube(reflectance=reflectance, emission=1.0))
    solution = solve(scene, solve_settings(method="hemicube", subdiv=4, solver="gauss-seidel",
                                          tolerance=1e-7), gpu=gpu)
    assert_physical(solution)
    row_sum = solution.report.details.form_factor_row_sum["min"]
    exact = 1.0 / (1 - reflectance)
    worst_bias = 1 - (1 - reflectance) / (1 - reflectance * row_sum)
    assert np.all(solution.patch_radiosity <= exact * 1.001)
    assert np.all(solution.patch_radiosity >= exact * (1 - worst_bias) * 0.999)


@pytest.mark.parametrize("solver", SOLVERS)
def test_divergent_system_is_refused_not_returned(gpu, solver):
    """A spectral radius above 1 (reflectance 1.05 with rows summing to 1) must raise, not return."""
    count = 16
    form_factors = np.full((count, count), 1.0 / (count - 1), dtype=np.float32)
    np.fill_diagonal(form_factors, 0)
    reflectance = np.full((count, 3), 1.05)
    emission = np.ones((count, 3))
    monitor = linear_solvers.Convergence(solver, 1e-6, 100_000)
    with pytest.raises(SolveError, match="diverged"):
        linear_solvers.solve_linear(gpu, solver, form_factors, reflectance, emission, monitor)


@pytest.mark.parametrize("solver", SOLVERS)
def test_iteration_cap_is_reported(gpu, solver):
    scene = scene_from_dict(closed_cube(reflectance=0.999, emission=1.0))
    with pytest.raises(SolveError, match="did not converge|stalled"):
        solve(scene, hemicube(solver=solver, tolerance=1e-9, max_iterations=64), gpu=gpu)


# --- scale and emission invariance ---------------------------------------------------------------

def scaled_scene(scene_dict: dict, length: float = 1.0, emission: float = 1.0) -> dict:
    return {"surfaces": [
        {**entry, "vertices": (np.asarray(entry["vertices"]) * length).tolist(),
         "emission": (np.asarray(entry["emission"]) * emission).tolist()}
        for entry in scene_dict["surfaces"]
    ]}


@pytest.fixture(scope="module")
def cornell_dict():
    return load_scene("cornell-box").to_dict()


@pytest.fixture(scope="module")
def cornell_baseline(gpu, cornell_dict):
    return solve(scene_from_dict(cornell_dict), hemicube(subdiv=3, hemicube_res=64, solver="gauss-seidel",
                                                         refinements=0), gpu=gpu)


@pytest.mark.parametrize("length, emission", [(1e-4, 1.0), (1e4, 1.0), (1.0, 1e6)])
def test_cornell_box_is_scale_and_emission_invariant(gpu, cornell_dict, cornell_baseline, length, emission):
    scene = scene_from_dict(scaled_scene(cornell_dict, length, emission))
    # no refinement: its split decisions compare float32 light with a threshold, and a patch on
    # the edge may go either way at another scale (the solve itself is what this test measures)
    solution = solve(scene, hemicube(subdiv=3, hemicube_res=64, solver="gauss-seidel", refinements=0), gpu=gpu)
    assert_physical(solution)
    expected = cornell_baseline.patch_radiosity
    ours = solution.patch_radiosity / emission
    area = solution.patches.area[:, None] / length**2
    relative_rms = np.sqrt((area * (ours - expected) ** 2).sum() / (area * expected**2).sum())
    assert relative_rms < 0.01
    # and patch by patch, relative to the brightest reflecting patch (dark patches have ~no signal)
    reflecting = solution.patches.emission.max(axis=1) == 0
    scale = expected[reflecting].max()
    assert np.abs(ours - expected)[reflecting].max() < 0.01 * scale


# --- 10 000 patches: fp32 accumulation -----------------------------------------------------------

def test_ten_thousand_patch_gpu_jacobi_matches_float64(gpu):
    """Rows of 10 000 equal fp32 form factors: the worst case for a running fp32 sum (all terms of
    one sign and size). Exact float64 answer of the same (fp32-rounded) system in closed form."""
    count, reflectance = 10_000, 0.25  # ρ = 0.25: 16 sweeps (one check) leave a tail of 0.25^16
    factor = np.float32(1.0 / (count - 1))
    form_factors = np.full((count, count), factor, dtype=np.float32)
    np.fill_diagonal(form_factors, 0)
    emission = np.random.default_rng(6).uniform(0, 1, size=(count, 3))
    emission[::7] = 0  # some patches do not emit
    rho_f = reflectance * float(factor)
    # B_i (1 + ρf) = E_i + ρf S,  S = Σ B  ⇒  S = ΣE / (1 + ρf − ρf N)
    total = emission.sum(axis=0) / (1 + rho_f - rho_f * count)
    exact = (emission + rho_f * total) / (1 + rho_f)
    monitor = linear_solvers.Convergence("jacobi-gpu", 1e-6, 1000)
    radiosity = linear_solvers.jacobi_gpu(gpu, form_factors, np.full((count, 3), reflectance), emission, monitor)
    relative = np.abs(radiosity - exact).max() / exact.max()
    # Stated bound: 5e-6 of max B for the accumulated rounding (measured 7.5e-7 on llvmpipe). The
    # shader keeps two partial sums of 5 000 terms; a running sum of 5 000 equal terms may drift
    # by up to 5 000 × 2^-24 ≈ 3e-4 of the gathered part in the worst case (here ρΣFB ≈ 0.2 max B).
    assert relative < 5e-6, f"fp32 accumulation error {relative:.3g} of max B"


# --- near-singular geometry ----------------------------------------------------------------------

def test_touching_perpendicular_patches_have_no_spikes(gpu):
    """Patches along a shared edge: r → 0 in cos cos / (π r²). A point on the edge sees the emitter
    fill half its hemisphere (F = 1/2), so ρ E / 2 bounds every patch."""
    scene = scene_from_dict(perpendicular_squares(receiver_reflectance=0.5, emitter_emission=1.0))
    for skips in (False, True):  # hemi-cubes, and the analytic unoccluded kernel
        solution = solve(scene, hemicube(subdiv=16, hemicube_res=64, skip_unneeded=skips), gpu=gpu)
        assert_physical(solution)
        receiver = solution.patches.surface == 0
        values = solution.patch_radiosity[receiver]
        assert values.max() <= 0.5 * 0.5
        area = solution.patches.area[receiver]
        mean = (values[:, 0] * area).sum() / area.sum()
        assert mean == pytest.approx(0.5 * 0.200044, rel=0.05)


def centre_point_reference(solution, emitter_index: int, scene) -> np.ndarray:
    """ρ E F(centre → emitter) per receiving patch, by Lambert's contour formula (float64)."""
    patches = solution.patches
    emitter = scene.surfaces[emitter_index]
    factors = point_to_polygon(patches.center, patches.normal, emitter.vertices[None])[:, 0]
    return patches.reflectance[:, 0] * emitter.emission[0] * factors


def receiver_against_centre_points(scene, gpu):
    """Hemi-cube radiosity of surface 0's patches (red) and Lambert's centre-point reference for it."""
    solution = solve(scene, hemicube(subdiv=8, hemicube_res=128), gpu=gpu)
    assert_physical(solution)
    receiving = solution.patches.surface == 0
    return solution.patch_radiosity[receiving, 0], centre_point_reference(solution, 1, scene)[receiving]


def test_grazing_light_stays_bounded(gpu):
    """An emitter standing 1 % of its size above the receiver's plane, beside it: light arrives at
    grazing angles, where hemi-cube side-face pixels carry almost no weight."""
    receiver = [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]]
    emitter = [[1.2, 0, 0.01], [1.2, 0, 0.51], [1.2, 1, 0.51], [1.2, 1, 0.01]]  # faces −x, towards the receiver
    scene = scene_from_dict({"surfaces": [surface("receiver", receiver, 0.5, 0.0),
                                          surface("emitter", emitter, 0.0, 1.0)]})
    ours, reference = receiver_against_centre_points(scene, gpu)
    assert np.abs(ours - reference).max() < 0.02 * reference.max()  # measured 0.5 %
    assert ours.sum() == pytest.approx(reference.sum(), rel=0.01)


def test_long_thin_sliver_has_no_spikes(gpu):
    """A 100:1 sliver receiver under a square emitter: patches 100× longer than wide."""
    receiver = [[0, 0, 0], [2, 0, 0], [2, 0.02, 0], [0, 0.02, 0]]
    scene = scene_from_dict({"surfaces": [surface("receiver", receiver, 0.5, 0.0),
                                          opposed_squares(0.5)["surfaces"][1]]})
    ours, reference = receiver_against_centre_points(scene, gpu)
    assert np.abs(ours - reference).max() < 0.03 * reference.max()  # measured 0.8 %


# --- the progressive method ----------------------------------------------------------------------

def progressive(**overrides) -> SolveSettings:
    settings = dict(method="progressive", subdiv=1, elements=2)
    return solve_settings(**(settings | overrides))


def test_progressive_closed_box_high_reflectance_stops_at_budget_from_below(gpu):
    """ρ = 0.99 needs ~100× the emitted power shot; at a shot budget the answer must be below the
    exact one by what is still unshot (never above, never NaN), and the float64 ledger must balance.
    The remainder's completion (the default) then adds what that unshot power would deliver."""
    reflectance = 0.99
    scene = scene_from_dict(closed_cube(reflectance=reflectance, emission=1.0))
    solution = solve(scene, progressive(max_shots=240, complete_remainder=False), gpu=gpu)
    assert solution.report.details.stop_reason == "max_shots"
    assert_physical(solution)
    exact = 1.0 / (1 - reflectance)
    radiosity = solution.patch_radiosity
    assert np.all(radiosity <= exact * 1.001) and radiosity.mean() < 0.8 * exact
    energy = solution.report.details.energy
    booked = energy["absorbed"] + energy["escaped"] + energy["unshot"]
    assert abs(energy["emitted"] + energy["surplus"] - booked) < 1e-9 * energy["emitted"]
    assert energy["escaped"] < 0.01 * energy["emitted"]  # a closed box: (almost) nothing escapes
    assert energy["surplus"] < 1e-4 * energy["emitted"]  # point-sampled factors summing a little over 1
    # in a uniform closed box, unshot radiosity U/A still adds ρ/(1 − ρ) U/A everywhere
    unshot_radiosity = energy["unshot"] / 3 / solution.patches.area.sum()
    completed = radiosity.mean() + unshot_radiosity * reflectance / (1 - reflectance)
    assert completed == pytest.approx(exact, rel=0.01)  # measured 5e-6
    # the solve's own completion, from the hit and reflected fractions its shots measured
    own = solve(scene, progressive(max_shots=240), gpu=gpu)
    assert own.patch_radiosity.mean() == pytest.approx(exact, rel=0.01)
    assert np.all(own.patch_radiosity <= exact * 1.01)


@pytest.fixture(scope="module")
def cornell_progressive_baseline(gpu, cornell_dict):
    return solve(scene_from_dict(cornell_dict), progressive(subdiv=2, tolerance=1e-2), gpu=gpu)


@pytest.mark.parametrize("length, emission", [(1e-4, 1.0), (1e4, 1.0), (1.0, 1e6)])
def test_progressive_is_scale_and_emission_invariant(gpu, cornell_dict, cornell_progressive_baseline,
                                                     length, emission):
    scene = scene_from_dict(scaled_scene(cornell_dict, length, emission))
    solution = solve(scene, progressive(subdiv=2, tolerance=1e-2), gpu=gpu)
    assert_physical(solution)
    expected = cornell_progressive_baseline.element_radiosity
    ours = solution.element_radiosity / emission
    assert np.all(np.isfinite(ours))
    reflecting = solution.patches.emission.max(axis=1) == 0
    difference = np.abs(ours - expected)[reflecting]
    assert difference.max() < 0.01 * expected[reflecting].max()


def test_progressive_touching_patches_have_no_spikes(gpu):
    scene = scene_from_dict(perpendicular_squares(receiver_reflectance=0.5, emitter_emission=1.0))
    solution = solve(scene, progressive(subdiv=4, elements=4, tolerance=1e-3), gpu=gpu)
    assert_physical(solution)
    elements = solution.element_radiosity[solution.patches.surface == 0]
    assert np.all(np.isfinite(elements)) and np.all(elements >= 0)
    assert elements.max() <= 0.5 * 0.5 * 1.01  # ρ E F with F ≤ 1/2 at the shared edge
    receiver = solution.patches.surface == 0
    area = solution.patches.area[receiver]
    mean = (solution.patch_radiosity[receiver, 0] * area).sum() / area.sum()
    assert mean == pytest.approx(0.5 * 0.200044, rel=0.05)

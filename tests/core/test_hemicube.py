"""Hemi-cube form factors and the linear solvers against exact references (docs/architecture.md oracles)."""

import numpy as np
import pytest
from scenes import area_weighted_mean, closed_cube, opposed_rectangles_form_factor, opposed_squares, perpendicular_squares, solve_settings

from radiosity_addon.core import hemicube, visibility
from radiosity_addon.core.hemicube import linear_solvers
from radiosity_addon.core import subdivide
from radiosity_addon.core import scene_from_dict
from radiosity_addon.core import SolveError
from radiosity_addon.core import solve

pytestmark = pytest.mark.gl  # covers every shader and pass: run again on zink (make test-zink)

SOLVERS = ["jacobi-gpu", "jacobi-cpu", "gauss-seidel"]
# subdivided 8 x 8, 2 x 2 hemi-cubes per patch, no refinement: the patches the test names
HEMICUBES_AT_256 = solve_settings(method="hemicube", subdiv=8, hemicube_res=256, skip_unneeded=False, refinements=0)


def test_opposed_rectangle_formula_matches_design_values():
    assert opposed_rectangles_form_factor(1, 1, 1) == pytest.approx(0.199825, abs=1e-6)
    assert opposed_rectangles_form_factor(1, 1, 0.5) == pytest.approx(0.415253, abs=1e-6)
    assert opposed_rectangles_form_factor(1, 1, 2) == pytest.approx(0.068590, abs=1e-6)


def test_delta_form_factors_normalized_and_unnormalized_excess():
    resolution = 64
    raw = visibility.delta_form_factors(resolution, normalize=False)
    # docs/architecture.md: unnormalized delta form factors sum to about 1 + 0.54 / N^2
    assert raw.sum() - 1 == pytest.approx(0.54 / resolution**2, rel=0.1)
    assert visibility.delta_form_factors(resolution).sum() == pytest.approx(1.0, abs=1e-12)
    assert visibility.fixed_point_weights(visibility.delta_form_factors(resolution)).sum(dtype=np.int64) == 2**31


@pytest.mark.parametrize("distance, exact", [(0.5, 0.415253), (1.0, 0.199825), (2.0, 0.068590)])
def test_opposed_squares_receiver_radiosity(gpu, distance, exact):
    scene = scene_from_dict(opposed_squares(distance))
    # skips off: nothing occludes here, so the analysis would use analytic factors instead
    solution = solve(scene, HEMICUBES_AT_256, gpu=gpu)
    assert solution.report.work.hemicubes == 4 * 128
    assert solution.report.work.bright_columns == 0  # the receiver reflects no light bright enough to alias
    mean = area_weighted_mean(solution, 0)
    np.testing.assert_allclose(mean, 0.5 * exact, rtol=0.03)


def test_perpendicular_squares_receiver_radiosity(gpu):
    scene = scene_from_dict(perpendicular_squares())
    solution = solve(scene, HEMICUBES_AT_256, gpu=gpu)
    assert solution.report.work.hemicubes == 4 * 128
    np.testing.assert_allclose(area_weighted_mean(solution, 0), 0.5 * 0.200044, rtol=0.04)


def test_single_patch_gives_centre_point_factor(gpu):
    """Unsubdivided, the hemi-cube gives the centre-point factor: +20 % at distance 1 (docs/architecture.md)."""
    scene = scene_from_dict(opposed_squares(1.0))
    patches = subdivide(scene, 1)
    matrix = hemicube.form_factor_matrix(gpu, patches, 256, scene.diameter)
    assert matrix[0, 1] / 0.199825 - 1 == pytest.approx(0.20, abs=0.02)
    assert matrix[0, 0] == 0 and matrix[1, 1] == 0  # a planar patch cannot see itself


@pytest.mark.parametrize("skip_unneeded", [False, True])
def test_one_patch_takes_the_mean_of_its_direct_light_not_its_centres(gpu, skip_unneeded):
    """The direct light is measured at 4 x 4 points of the patch, not through its centre's hemi-cube:
    one unsubdivided receiver under an emitter gets the patch-to-patch factor (0.199825 at distance 1),
    where the centre-point factor is 20 % more (above). With skips off it is drawn by hemi-cubes, on:
    nothing occludes, and it is the analytic kernel; either way F carries only the reflected light."""
    scene = scene_from_dict(opposed_squares(1.0))
    settings = solve_settings(method="hemicube", subdiv=1, hemicube_res=64, hemicube_elements=1,
                             skip_unneeded=skip_unneeded, refinements=0)
    solution = solve(scene, settings, gpu=gpu)
    receiver = np.flatnonzero(solution.patches.surface == 0)
    np.testing.assert_allclose(solution.patch_radiosity[receiver], 0.5 * 0.199825, rtol=0.01)
    np.testing.assert_allclose(solution.patch_direct[receiver], 0.199825, rtol=0.01)
    np.testing.assert_allclose(solution.patch_light[receiver], 0.199825, rtol=0.01)


def test_closed_cube_rows_sum_to_one(gpu):
    scene = scene_from_dict(closed_cube())
    patches = subdivide(scene, 4)
    matrix = hemicube.form_factor_matrix(gpu, patches, 64, scene.diameter)
    np.testing.assert_allclose(matrix.sum(axis=1), 1.0, atol=1e-3)
    # reciprocity A_i F_ij = A_j F_ji holds approximately (hemi-cube aliasing)
    flux = patches.area[:, None] * matrix
    big = flux > 0.002 * patches.area.max()
    assert np.median(np.abs(flux - flux.T)[big] / flux[big]) < 0.05


@pytest.mark.parametrize("solver", SOLVERS)
@pytest.mark.parametrize("reflectance", [0.5, 0.9])
@pytest.mark.parametrize("skip_unneeded", [False, True], ids=["hemicubes", "analysed"])
def test_furnace(gpu, solver, reflectance, skip_unneeded):
    """Closed cube, uniform ρ and E: B = E/(1 − ρ). Analysed, the convex grey cube is solved
    with analytic unoccluded form factors on one channel; with skips off, by hemi-cubes."""
    scene = scene_from_dict(closed_cube(reflectance=reflectance, emission=1.0))
    settings = solve_settings(method="hemicube", subdiv=3, hemicube_res=64, solver=solver, tolerance=1e-6,
                             skip_unneeded=skip_unneeded, hemicube_elements=1)
    solution = solve(scene, settings, gpu=gpu)
    assert solution.report.work.hemicubes == (0 if skip_unneeded else 54)
    np.testing.assert_allclose(solution.patch_radiosity, 1 / (1 - reflectance), rtol=0.01)


def test_solvers_agree_on_cornell_box(gpu):
    from radiosity_addon.core import load_scene

    scene = load_scene("cornell-box")
    results = [solve(scene, solve_settings(method="hemicube", subdiv=2, hemicube_res=64, solver=s,
                                          tolerance=1e-7), gpu=gpu).patch_radiosity for s in SOLVERS]
    scale = results[1].max()
    for other in (results[0], results[2]):
        assert np.abs(other - results[1]).max() / scale < 1e-5


def two_patch_system():
    form_factors = np.array([[0.0, 0.3], [0.45, 0.0]])
    reflectance = np.array([[0.8, 0.5, 0.2], [0.6, 0.7, 0.9]])
    emission = np.array([[0.0, 0.0, 0.0], [2.0, 1.0, 3.0]])
    return form_factors, reflectance, emission


@pytest.mark.parametrize("solver", SOLVERS)
def test_two_patch_closed_form(gpu, solver):
    """B1 = (E1 + ρ1 F12 E2)/(1 − ρ1ρ2F12F21), B2 = E2 + ρ2 F21 B1 (docs/architecture.md)."""
    form_factors, rho, emission = two_patch_system()
    f12, f21 = form_factors[0, 1], form_factors[1, 0]
    b1 = (emission[0] + rho[0] * f12 * emission[1]) / (1 - rho[0] * rho[1] * f12 * f21)
    b2 = emission[1] + rho[1] * f21 * b1
    monitor = linear_solvers.Convergence(solver, 1e-7, 10_000)
    result = linear_solvers.solve_linear(gpu, solver, form_factors, rho, emission, monitor)
    np.testing.assert_allclose(result, np.stack([b1, b2]), rtol=1e-5)


def test_iteration_cap_is_a_clear_error(gpu):
    form_factors, rho, emission = two_patch_system()
    monitor = linear_solvers.Convergence("jacobi-cpu", 1e-12, 3)
    with pytest.raises(SolveError, match="did not converge in 3 iterations"):
        linear_solvers.jacobi_cpu(form_factors, rho, emission, monitor)


def test_divergence_is_a_clear_error():
    """An unphysical system (row sums × ρ > 1) must stop with a message, never run away silently."""
    form_factors = np.full((4, 4), 0.9) - np.diag([0.9] * 4)
    rho = np.full((4, 3), 0.9)
    emission = np.ones((4, 3))
    monitor = linear_solvers.Convergence("jacobi-cpu", 1e-9, 100_000)
    with pytest.raises(SolveError, match="diverged"):
        linear_solvers.jacobi_cpu(form_factors, rho, emission, monitor)


def test_matrix_memory_guard_suggests_progressive():
    with pytest.raises(SolveError, match="progressive"):
        hemicube.check_memory(100_000, 2 << 30)


def small_patch_over_receiver(height=1.0, side=0.05, offset=(0.54, 0.54)):
    """The unit receiver of `opposed_squares` with, `height` above it, a `side`-wide square facing down."""
    scene = opposed_squares(height)
    x, y = offset
    square = [[x, y], [x + side, y], [x + side, y + side], [x, y + side]]
    scene["surfaces"][1]["vertices"] = [[u, v, height] for u, v in square][::-1]
    return scene


def test_bright_patch_columns_are_shot_where_a_coarse_hemicube_misses_a_small_patch(gpu):
    """A 5 cm patch 1 m over a receiver: the 16-pixel hemi-cube sees it as a pixel or nothing;
    shot from the patch (bright_columns), the receiver's factor is the exact point-to-polygon
    one averaged over the same 2 x 2 points, within 2 %."""
    from radiosity_addon.core.hemicube import analytic
    from radiosity_addon.core.hemicube.bright_columns import shot_columns
    from radiosity_addon.core.shooting.sky import element_frames

    scene = scene_from_dict(small_patch_over_receiver())
    patches = subdivide(scene, 1)
    shot = shot_columns(gpu, scene, patches, np.array([1]), np.array([0]), 1, 2, "hemicube", 256, True)
    points = element_frames(patches, 2, np.array([0]))[0]
    exact = analytic.point_to_polygon(points, np.repeat(patches.normal[:1], 4, axis=0), patches.corners[1:2]).mean()
    assert shot.shape == (1, 1)
    assert shot[0, 0] == pytest.approx(exact, rel=0.02)
    # why: at 16 pixels the hemi-cube at the receiver's centre sees the patch as the one pixel whose
    # centre it covers (0.125 wide at 1 m), several times the patch's own 5 cm
    rasterized = hemicube.form_factor_matrix(gpu, patches, 16, scene.diameter)[0, 1]
    at_centre = analytic.point_to_polygon(patches.center[:1], patches.normal[:1], patches.corners[1:2])[0]
    assert rasterized / at_centre > 3


def test_bright_patches_are_the_brightest_few_above_the_ratio():
    from radiosity_addon.core.hemicube import bright_columns

    scene = scene_from_dict(closed_cube())
    patches = subdivide(scene, 16)  # 1 536 patches of equal area
    reflected = np.full((len(patches), 3), 0.1)
    reflected[[3, 7, 11]] = [[50.0] * 3, [40.0] * 3, [30.0] * 3]
    rows = np.arange(len(patches))
    assert bright_columns.bright_patches(patches, reflected, rows).tolist() == [3, 7, 11]
    assert bright_columns.bright_patches(patches, reflected, rows[rows != 7]).tolist() == [3, 11]
    assert bright_columns.bright_patches(patches, np.full((len(patches), 3), 0.1), rows).tolist() == []
    dim_rest = np.ones((len(patches), 3))
    dim_rest[[3, 7, 11]] = 50.0  # bright, but 150 of 1 683 of the power reflected: below MIN_POWER_SHARE
    assert bright_columns.bright_patches(patches, dim_rest, rows).tolist() == []
    limited = np.full((len(patches), 3), 0.01)
    limited[:bright_columns.MAX_BRIGHT_PATCHES + 5] = np.arange(bright_columns.MAX_BRIGHT_PATCHES + 5)[:, None] + 100.0
    chosen = bright_columns.bright_patches(patches, limited, rows)  # all above the ratio: the brightest kept
    assert chosen.tolist() == list(range(5, bright_columns.MAX_BRIGHT_PATCHES + 5))


def square(x, y, z, side, facing_up=True):
    corners = [[x, y, z], [x + side, y, z], [x + side, y + side, z], [x, y + side, z]]
    return corners if facing_up else corners[::-1]


def test_shot_columns_keep_every_shot_apart_element_by_element(gpu):
    """Two receivers of 2 x 2 elements, four small patches 1 m over them shot in one pass: every
    (element, patch) entry is the exact point-to-polygon factor at the element's centre, to 2 %
    (a shot summed into another's column, or elements out of order, would miss it)."""
    from radiosity_addon.core.hemicube import analytic
    from radiosity_addon.core.hemicube.bright_columns import shot_columns
    from radiosity_addon.core.shooting.sky import element_frames
    from scenes import surface

    small = [square(x, y, 1.0, 0.05, facing_up=False) for x, y in [(0.1, 0.2), (0.7, 0.3), (1.5, 0.8), (2.0, 0.1)]]
    scene = scene_from_dict({"surfaces": [surface("a", square(0, 0, 0, 1), 0.5, 0), surface("b", square(1.2, 0, 0, 1), 0.5, 0)]
                             + [surface(f"s{k}", corners, 0.5, 1.0) for k, corners in enumerate(small)]})  # emitting: a valid scene
    patches = subdivide(scene, 1)
    rows, columns = np.flatnonzero(patches.surface < 2), np.flatnonzero(patches.surface >= 2)
    shot = shot_columns(gpu, scene, patches, columns, rows, 2, 2, "hemicube", 256, True)
    centres = element_frames(patches, 2, rows)[0]
    normals = np.repeat(patches.normal[rows], 4, axis=0)
    exact = analytic.point_to_polygon(centres, normals, patches.corners[columns])  # (points, polygons)
    assert shot.shape == (8, 4)
    np.testing.assert_allclose(shot, exact, rtol=0.02)


def test_bright_columns_replace_only_far_thinly_sampled_entries(gpu):
    """A bright 5 cm patch 5 cm over a small receiver and 1 m over a large one: the near
    receiver keeps its hemi-cube entry, the far one takes the shot value where the hemi-cube saw
    less than WELL_SAMPLED of the patch, and keeps a well-sampled entry."""
    from radiosity_addon.core.hemicube import analytic
    from radiosity_addon.core.hemicube.bright_columns import WELL_SAMPLED, shoot_bright_columns
    from radiosity_addon.core.shooting.sky import element_frames
    from scenes import surface

    scene = scene_from_dict({"surfaces": [surface("near", square(0.0, 0.0, 0.0, 0.1), 0.5, 0),
                                          surface("far", square(2.0, 2.0, -0.95, 1.0), 0.5, 0),  # off to the side: the near one hides nothing
                                          surface("bright", square(0.025, 0.025, 0.05, 0.05, facing_up=False), 0.5, 1.0)]})
    patches = subdivide(scene, 1)
    near, far, bright = (int(np.flatnonzero(patches.surface == s)[0]) for s in range(3))
    reflected = np.ones((len(patches), 3))
    reflected[bright] = 1000.0  # 71 % of the power reflected
    rows = np.arange(len(patches))
    settings = solve_settings(visibility_res=256)
    element_rows = np.zeros((len(patches), len(patches)), dtype=np.float32)
    element_rows[[near, far], bright] = WELL_SAMPLED / 2
    assert shoot_bright_columns(gpu, scene, patches, element_rows, rows, 1, reflected, settings).tolist() == [bright]
    points = element_frames(patches, 2, np.array([far]))[0]
    exact = analytic.point_to_polygon(points, np.repeat(patches.normal[far:far + 1], 4, axis=0),
                                      patches.corners[bright:bright + 1]).mean()
    assert element_rows[near, bright] == np.float32(WELL_SAMPLED / 2)
    assert element_rows[far, bright] == pytest.approx(exact, rel=0.02)
    assert exact < WELL_SAMPLED / 4  # the replaced entry did change
    element_rows[far, bright] = 2 * WELL_SAMPLED
    shoot_bright_columns(gpu, scene, patches, element_rows, rows, 1, reflected, settings)
    assert element_rows[far, bright] == np.float32(2 * WELL_SAMPLED)


def test_widened_product_sums_a_float32_matrix_in_float64_block_by_block():
    rng = np.random.default_rng(3)
    matrix = rng.random((1300, 700), dtype=np.float32)
    vectors = rng.random((700, 3))
    exact = matrix.astype(np.float64) @ vectors
    np.testing.assert_allclose(linear_solvers.widened_product(matrix, vectors, block=512), exact, rtol=1e-13)
    assert np.abs(matrix @ vectors.astype(np.float32) / exact - 1).max() > 1e-8  # float32 sums would not


@pytest.mark.parametrize("tolerance", [1e-5, 1e-7])  # float32 sums, float64 sums (SINGLE_SUMS_TOLERANCE)
def test_gauss_seidel_stops_near_the_converged_solution_in_either_precision(tolerance):
    rng = np.random.default_rng(4)
    count = 600
    form_factors = rng.random((count, count), dtype=np.float32) * np.float32(1.8 / count)
    np.fill_diagonal(form_factors, 0)
    reflectance, emission = rng.uniform(0.3, 0.9, (count, 3)), rng.random((count, 3))
    exact = np.linalg.solve(np.eye(count)[None] - reflectance.T[:, :, None] * form_factors.astype(np.float64)[None],
                            emission.T[:, :, None])[:, :, 0].T
    solved = linear_solvers.gauss_seidel(form_factors, reflectance, emission,
                                         linear_solvers.Convergence("gauss-seidel", tolerance, 1000))
    assert np.abs(solved - exact).max() / exact.max() < 10 * tolerance

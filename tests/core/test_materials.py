"""Textured materials and what a lightmap holds: material maps give patches the mean albedo and
emission of their texels, a "light" lightmap holds H, a "combined" one B = E + ρH texel by texel."""

from __future__ import annotations

import numpy as np
import pytest
from scenes import lightmap_settings, solve_settings, surface

from radiosity_addon.core import (MaterialMap, bake_lightmaps, lightmap_sizes,
                                  scene_from_dict, solve, surfaces_with_material_maps)
from radiosity_addon.core.uvspace import footprint_means

FLOOR_UV = [[0, 0], [1, 0], [1, 1], [0, 1]]  # the 0.5 m patches of the 2 m floor fall on 1/4 UV squares


def lit_floor(reflectance=0.5) -> dict:
    floor = surface("floor", [[0, 0, 0], [2, 0, 0], [2, 2, 0], [0, 2, 0]], reflectance, 0.0)
    floor["uv"] = FLOOR_UV
    lamp = surface("lamp", [[0.5, 0.5, 1.5], [0.5, 1.5, 1.5], [1.5, 1.5, 1.5], [1.5, 0.5, 1.5]], 0.0, 4.0)
    lamp["uv"] = [[0.1, 0.1], [0.1, 0.9], [0.9, 0.9], [0.9, 0.1]]
    return {"surfaces": [floor, lamp]}


def checker(size, squares=4, low=0.2, high=0.8) -> np.ndarray:
    """An albedo map (H, W, 3): a checker of `squares` x `squares` in the UV square [0, 1]²."""
    width, height = size
    v, u = np.meshgrid((np.arange(height) + 0.5) / height, (np.arange(width) + 0.5) / width, indexing="ij")
    odd = (np.floor(u * squares) + np.floor(v * squares)) % 2 == 1
    values = np.where(odd, high, low)
    return np.repeat(values[..., None], 3, axis=2).astype(np.float32)


def test_footprint_means_average_the_texels_inside():
    image = np.arange(16 * 16, dtype=np.float32).reshape(16, 16, 1)
    square = np.array([[[0.25, 0.25], [0.75, 0.25], [0.75, 0.75], [0.25, 0.75]]])  # texels 4..11 both ways
    from radiosity_addon.core import GPU

    with GPU() as gpu:
        means, texels = footprint_means(gpu, square, image)
    assert texels[0] == 64 and means[0, 0] == pytest.approx(image[4:12, 4:12].mean())


def test_light_and_combined_lightmaps_relate_as_b_equals_e_plus_rho_h(gpu):
    scene = scene_from_dict(lit_floor())
    solution = solve(scene, solve_settings(subdiv=4, elements=2, tolerance=1e-4), gpu=gpu)
    light = bake_lightmaps(scene, solution, lightmap_settings(texel_density=16), gpu=gpu)["floor"]
    combined = bake_lightmaps(scene, solution, lightmap_settings(texel_density=16, content="combined"),
                              gpu=gpu)["floor"]
    inside = light.patch_index >= 0
    assert light.content == "light" and combined.content == "combined"
    assert light.rgba[inside][:, :3].max() > 0.1
    np.testing.assert_allclose(combined.rgba[inside][:, :3], 0.5 * light.rgba[inside][:, :3], rtol=1e-5)
    # H holds what reaches a black floor too, where B is 0
    black = scene_from_dict(lit_floor(reflectance=0.0))
    black_solution = solve(black, solve_settings(subdiv=4, elements=2, tolerance=1e-4), gpu=gpu)
    black_light = bake_lightmaps(black, black_solution, lightmap_settings(texel_density=16), gpu=gpu)["floor"]
    np.testing.assert_allclose(black_light.rgba[inside][:, :3], light.rgba[inside][:, :3], rtol=1e-4)


def test_a_checker_texture_shows_texel_by_texel_in_combined_and_averages_in_transport(gpu):
    plain = scene_from_dict(lit_floor())
    settings = lightmap_settings(texel_density=16, content="combined")
    size = lightmap_sizes(plain, settings)["floor"]
    albedo = checker(size)
    maps = {"floor": MaterialMap(albedo=albedo, emission=np.zeros_like(albedo))}
    textured = surfaces_with_material_maps(gpu, plain, maps)
    assert textured.reflectance[0] == pytest.approx([0.5] * 3, abs=0.02)  # the checker's mean
    solution = solve(textured, solve_settings(subdiv=4, elements=2, tolerance=1e-4), gpu=gpu)
    # each 0.5 m patch covers one checker square: its reflectance is that square's albedo
    floor = (solution.patches.surface == 0) & ~solution.patches.is_back
    assert set(np.round(solution.patches.reflectance[floor, 0], 2)) == {0.2, 0.8}
    combined = bake_lightmaps(textured, solution, settings, gpu=gpu)["floor"]
    light = bake_lightmaps(textured, solution, lightmap_settings(texel_density=16), gpu=gpu)["floor"]
    inside = combined.patch_index >= 0
    np.testing.assert_allclose(combined.rgba[inside][:, :3], albedo[inside] * light.rgba[inside][:, :3], rtol=1e-5)
    # the light reaching the floor is smooth, the combined map shows the checker
    ratio = combined.rgba[..., 0][inside] / light.rgba[..., 0][inside]
    assert set(np.round(ratio.astype(float), 3).tolist()) == {0.2, 0.8}


def test_an_emission_map_lights_the_scene_by_its_mean():
    """An emissive panel whose emission comes only from its map (half of it glows): the scene has
    an emitter, and the panel's surface emits the map's mean."""
    from radiosity_addon.core import GPU

    data = lit_floor()
    data["surfaces"][1]["emission"] = [0, 0, 0]
    data["surfaces"].append(surface("spare", [[3, 0, 0], [4, 0, 0], [4, 1, 0], [3, 1, 0]], 0.5, 1.0))
    scene = scene_from_dict(data)
    size = lightmap_sizes(scene, lightmap_settings(texel_density=16))["lamp"]
    emission = np.zeros((size[1], size[0], 3), dtype=np.float32)
    emission[: size[1] // 2] = 2.0  # the half with v < 0.5
    maps = {"lamp": MaterialMap(albedo=np.zeros_like(emission), emission=emission)}
    with GPU() as gpu:
        textured = surfaces_with_material_maps(gpu, scene, maps)
    assert textured.emission[1, 0] == pytest.approx(1.0, rel=0.05)

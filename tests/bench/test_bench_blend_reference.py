"""blend_reference.py: Cycles' bake of a .blend on its Lightmap UVs against answers known in closed form.

- Planes under a sun of strength S (W/m²) with no angle, far apart (nothing reflects between
  them): the irradiance is S cos θ, so the light content is H = S cos θ / π and the combined
  content B = E + ρH. A plane whose back faces the sun bakes H = 0 (Cycles bakes the front).
- A closed box, every face emitting E and reflecting ρ: B = E/(1 − ρ) everywhere, H = B.
"""

from __future__ import annotations

import math

import blender_support  # noqa: F401  (before bpy: a temporary Blender user folder)
import bpy
import numpy as np
import pytest

from bench import blend_reference, compare
from bench.blend_scenes import (add_lamp, diffuse_material, lightmap_pack, mesh_object, reset,
                                                save_blend)
from bench.shapes import box

SUN_STRENGTH, SUN_FROM_ZENITH = 3.0, 30.0  # degrees; the sun turns about x
REFLECTANCE, EMISSION = (0.6, 0.4, 0.2), (0.1, 0.2, 0.3)
# object -> (tilt about x in degrees, cos θ to the sun)
PLANES = {"Lit": (0.0, math.cos(math.radians(30))), "Tilted": (-40.0, math.cos(math.radians(70))),
          "Back": (180.0, 0.0)}
SIZE = 16


def erode(mask: np.ndarray, texels: int) -> np.ndarray:
    """Texels at least `texels` from the mask's edge (Combined bakes wobble next to a chart's edge)."""
    for _ in range(texels):
        mask = mask.copy()
        mask[1:-1, 1:-1] &= mask[:-2, 1:-1] & mask[2:, 1:-1] & mask[1:-1, :-2] & mask[1:-1, 2:]
        mask[[0, -1], :] = False
        mask[:, [0, -1]] = False
    return mask


@pytest.fixture(scope="module")
def sun_planes(tmp_path_factory):
    """Three planes sharing one mesh and one material (linked duplicates), 50 m apart."""
    reset()
    material = diffuse_material("Shared", REFLECTANCE, EMISSION)
    first = mesh_object("Lit", [(-0.5, -0.5, 0), (0.5, -0.5, 0), (0.5, 0.5, 0), (-0.5, 0.5, 0)], [(0, 1, 2, 3)],
                        [material])
    for index, (name, (tilt, _)) in enumerate(PLANES.items()):
        obj = first if index == 0 else bpy.data.objects.new(name, first.data)
        if index:
            bpy.context.scene.collection.objects.link(obj)
        obj.location = (50.0 * index, 0.0, 0.0)
        obj.rotation_euler = (math.radians(tilt), 0.0, 0.0)
    add_lamp("Sun", "SUN", (0, 0, 10), (SUN_FROM_ZENITH, 0.0, 0.0), energy=SUN_STRENGTH, angle=0.0)
    lightmap_pack([first])
    path = tmp_path_factory.mktemp("reference") / "sun_planes.blend"
    save_blend(path)
    return path


@pytest.fixture(scope="module")
def furnace(tmp_path_factory):
    reset()
    vertices, faces = box((0, 0, 0), (1, 1, 1), inward=True)
    obj = mesh_object("Box", vertices, faces, [diffuse_material("Glow", (0.5, 0.5, 0.5), (1.0, 1.0, 1.0))])
    lightmap_pack([obj])
    path = tmp_path_factory.mktemp("reference") / "furnace.blend"
    save_blend(path)
    return path


SIZES = {name: (SIZE, SIZE) for name in PLANES}


def test_sun_light_and_combined_match_the_closed_form_on_every_object_in_one_call(sun_planes):
    light = blend_reference.bake_lightmaps(sun_planes, SIZES, "light", samples=4)["images"]
    combined = blend_reference.bake_lightmaps(sun_planes, SIZES, "combined", samples=4)["images"]
    for name, (_, cosine) in PLANES.items():
        baked = light[name][..., 3] > 0.5
        assert baked.sum() > 0.5 * SIZE**2, name
        assert (light[name][..., 3][~baked] == 0).all()  # what the bake did not reach stays unwritten
        exact_light = SUN_STRENGTH * cosine / math.pi
        np.testing.assert_allclose(light[name][baked][:, :3], exact_light, atol=1e-5, err_msg=name)
        interior = erode(combined[name][..., 3] > 0.5, 2)
        exact = np.array(EMISSION) + np.array(REFLECTANCE) * exact_light
        np.testing.assert_allclose(combined[name][interior][:, :3], np.broadcast_to(exact, (interior.sum(), 3)),
                                   rtol=3e-3, err_msg=name)


def test_one_call_bakes_what_object_by_object_calls_bake(sun_planes):
    together = blend_reference.bake_lightmaps(sun_planes, SIZES, "light", samples=4)["images"]
    apart = blend_reference.bake_lightmaps(sun_planes, SIZES, "light", samples=4, one_call=False)["images"]
    for name in PLANES:
        np.testing.assert_allclose(together[name], apart[name], atol=1e-6, err_msg=name)


def test_furnace_light_and_noise_estimate(furnace):
    sizes = {"Box": (32, 32)}
    reference = blend_reference.reference_with_noise(furnace, sizes, "light", samples=16)
    exact = 1.0 / (1 - 0.5)
    image = reference["images"]["Box"]
    baked = image[..., 3] > 0.5
    assert image[baked][:, :3].mean() == pytest.approx(exact, rel=0.02)
    combined = blend_reference.bake_lightmaps(furnace, sizes, "combined", samples=16)["images"]["Box"]
    assert combined[baked][:, :3].mean() == pytest.approx(1.0 + 0.5 * exact, rel=0.02)  # B = E + ρH
    # the half difference of two seeds is as large as the mean's own error
    texels = {"Box": baked}
    exact_image = {"Box": np.concatenate([np.full(image.shape[:2] + (3,), exact), image[..., 3:]], axis=-1)}
    error = compare.texel_relative_rms(reference["images"], exact_image, texels)
    noise = compare.relative_noise(reference["noise"], exact_image, texels)
    assert 0 < error < 0.2
    assert noise == pytest.approx(error, rel=0.25)


def test_cache_returns_the_same_arrays_without_baking_again(sun_planes, tmp_path, monkeypatch):
    sizes = {"Lit": (8, 8)}
    first = blend_reference.cycles_lightmaps(sun_planes, sizes, "combined", 2, seed=3, cache_dir=tmp_path)
    assert not first["cached"]

    def no_bake(*args, **kwargs):
        raise AssertionError("baked again")

    monkeypatch.setattr(blend_reference, "bake_lightmaps", no_bake)
    again = blend_reference.cycles_lightmaps(sun_planes, sizes, "combined", 2, seed=3, cache_dir=tmp_path)
    assert again["cached"] and again["seconds"] == first["seconds"]
    np.testing.assert_array_equal(again["images"]["Lit"], first["images"]["Lit"])
    with pytest.raises(AssertionError, match="baked again"):  # other samples: another key
        blend_reference.cycles_lightmaps(sun_planes, sizes, "combined", 3, seed=3, cache_dir=tmp_path)


def test_unknown_object_is_refused(sun_planes):
    with pytest.raises(ValueError, match="no object named 'Nope'"):
        blend_reference.bake_lightmaps(sun_planes, {"Nope": (4, 4)}, "light", samples=1)

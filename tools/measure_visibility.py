"""Measure the progressive method's visibility variants against a CPU ray cast.

For a spread of shooter patches of a scene, every receiver element in front of
the shooter and facing it is classified visible/hidden by the GPU item buffer
(each variant) and by `raycast.visible_from`. Prints the fraction classified
wrongly, the same over non-grazing pairs (both cosines > 0.05), and the
form-factor-weighted error (disk weights), which is what the energy sees.

    .venv/bin/python tools/measure_visibility.py [--scene cornell-box] [--subdiv 4] [--elements 4]
        [--resolution 512] [--search-radius R] [--variants plain tessellated search]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from radiosity_addon.core import gl  # noqa: E402
from radiosity_addon.core.element_textures import ElementTextures, element_centers  # noqa: E402
from radiosity_addon.core.patches import subdivide  # noqa: E402
from radiosity_addon.core.raycast import visible_from  # noqa: E402
from radiosity_addon.core.scene import load_scene  # noqa: E402
from radiosity_addon.core.shooting import Gatherer, PatchBuffers, patch_shooter  # noqa: E402
from radiosity_addon.core.visibility import VARIANTS, VisibilityMap  # noqa: E402


def measure(ctx, scene, patches, elements: int, resolution: int, variant: str, shooters, search_radius=None):
    """Dict of misclassification measures of one variant."""
    count = len(patches)
    x = element_centers(patches, elements).reshape(-1, 3)
    owner = np.repeat(np.arange(count), elements ** 2)
    normal = patches.normal[owner]
    radius = VARIANTS[variant].search_radius if search_radius is None else search_radius
    textures = ElementTextures(ctx, patches, elements)
    buffers = PatchBuffers(ctx, patches, textures)
    visibility_map = VisibilityMap(ctx, patches, resolution, variant, scene.diameter)
    gatherer = Gatherer(ctx, textures, buffers, "exact", radius, record_visibility=True)
    wrong = total = false_visible = false_hidden = 0
    wrong_steep = total_steep = 0
    weight_wrong = weight_visible = 0.0
    try:
        for s in shooters:
            shooter = patch_shooter(patches, s, np.zeros(3))
            visibility_map.render(shooter.position, shooter.axes, skip_patch=s)
            gatherer.shoot(shooter, visibility_map)
            gpu = gatherer.recorded_visibility() > 0.5
            d = x - shooter.position
            r = np.linalg.norm(d, axis=1)
            cos_shooter = (d @ shooter.axes[2]) / r
            cos_receiver = -(normal * d).sum(axis=1) / r
            candidate = (cos_shooter > 1e-9) & (cos_receiver > 1e-9) & (owner != s)
            ref = visible_from(shooter.position, x[candidate], patches, owner[candidate])
            got = gpu[candidate]
            bad = got != ref
            wrong += bad.sum()
            total += candidate.sum()
            false_visible += (got & ~ref).sum()
            false_hidden += (~got & ref).sum()
            steep = (cos_shooter[candidate] > 0.05) & (cos_receiver[candidate] > 0.05)
            wrong_steep += (bad & steep).sum()
            total_steep += steep.sum()
            area = shooter.area
            weight = area * cos_shooter[candidate] * cos_receiver[candidate] / (np.pi * r[candidate] ** 2 + area)
            weight_wrong += weight[bad].sum()
            weight_visible += weight[ref].sum()
    finally:
        for obj in (gatherer, visibility_map, buffers, textures):
            obj.release()
    return {"variant": variant, "search_radius": radius, "misclassified": wrong / total,
            "false_visible": int(false_visible), "false_hidden": int(false_hidden), "candidates": int(total),
            "misclassified_non_grazing": wrong_steep / max(total_steep, 1),
            "form_factor_weighted_error": weight_wrong / weight_visible}


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scene", default="cornell-box")
    parser.add_argument("--subdiv", type=int, default=4)
    parser.add_argument("--elements", type=int, default=4)
    parser.add_argument("--resolution", type=int, default=512)
    parser.add_argument("--shooters", type=int, default=16, help="number of shooter patches, spread evenly")
    parser.add_argument("--search-radius", type=int, default=None, help="override the search variant's radius")
    parser.add_argument("--variants", nargs="+", default=list(VARIANTS))
    args = parser.parse_args()
    scene = load_scene(args.scene)
    patches = subdivide(scene, args.subdiv)
    shooters = np.linspace(0, len(patches) - 1, args.shooters).round().astype(int)
    ctx = gl.create_context()
    for variant in args.variants:
        radius = args.search_radius if variant == "search" else None
        m = measure(ctx, scene, patches, args.elements, args.resolution, variant, shooters, radius)
        print(f"{variant:12s} radius {m['search_radius']}  misclassified {m['misclassified']:.4f}"
              f" (false visible {m['false_visible']}, false hidden {m['false_hidden']} of {m['candidates']})"
              f"  non-grazing {m['misclassified_non_grazing']:.4f}"
              f"  form-factor weighted {m['form_factor_weighted_error']:.4f}")


if __name__ == "__main__":
    main()

"""Measure the progressive method's visibility variants against a CPU ray cast.

For a spread of shooter patches of a scene, every receiver element in front of
the shooter and facing it is classified visible/hidden by the GPU item buffer
(each variant) and by the ray cast `visible_from` of tests/oracles.py. Prints the fraction classified
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

ROOT = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT), str(ROOT / "tests")]  # the oracles are the tests' own

from oracles import visibility_misclassification  # noqa: E402

from radiosity_addon.core import GPU, load_scene, subdivide  # noqa: E402
from radiosity_addon.core.visibility import VARIANTS  # noqa: E402


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
    with GPU() as gpu:
        for variant in args.variants:
            radius = args.search_radius if variant == "search" else None
            m = visibility_misclassification(gpu, scene, patches, args.elements, args.resolution, variant, shooters,
                                             radius)
            print(f"{variant:12s} radius {m['search_radius']}  misclassified {m['misclassified']:.4f}"
                  f" (false visible {m['false_visible']}, false hidden {m['false_hidden']} of {m['candidates']})"
                  f"  non-grazing {m['misclassified_non_grazing']:.4f}"
                  f"  form-factor weighted {m['form_factor_weighted_error']:.4f}")


if __name__ == "__main__":
    main()

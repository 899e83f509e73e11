"""The bundled Cornell box with its light hung `gap` under the ceiling (dev only, like the rest of
the benchmark): a ceiling panel as users model one, an emissive plane just below the ceiling.
The sample's light is 5 mm under it; at 1 mm the ceiling around the light is where a baker's
interpolation shows (a dark ring) and where the light's back lights the ceiling right above it.

    python -m bench.cornell_gap --gap 0.001 --output out/cornell/cornell_1mm.blend
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import bpy

SAMPLE = Path(__file__).resolve().parents[2] / "sample_blends" / "cornell_box.blend"


def save_cornell_gap(path: Path, gap: float, sample: Path = SAMPLE) -> float:
    """Write the sample with its light `gap` under the ceiling to `path`; returns the light's height."""
    bpy.ops.wm.open_mainfile(filepath=str(sample), load_ui=False)
    light, ceiling = bpy.data.objects["light"], bpy.data.objects["ceiling"]
    top = max((ceiling.matrix_world @ vertex.co).z for vertex in ceiling.data.vertices)
    height = max((light.matrix_world @ vertex.co).z for vertex in light.data.vertices)
    light.location.z += (top - gap) - height
    bpy.context.view_layer.update()
    path.parent.mkdir(parents=True, exist_ok=True)
    bpy.ops.wm.save_as_mainfile(filepath=str(path.resolve()))
    return top - gap


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(prog="python -m bench.cornell_gap",
                                     description=__doc__.split("\n")[0])
    parser.add_argument("--gap", type=float, required=True, help="metres between the light and the ceiling")
    parser.add_argument("--output", type=Path, required=True, metavar="FILE.blend")
    args = parser.parse_args(argv)
    if not SAMPLE.exists():
        print(f"error: {SAMPLE} is missing; make it with `make samples`", file=sys.stderr)
        return 1
    height = save_cornell_gap(args.output, args.gap)
    print(f"{args.output}: the light {args.gap * 1000:g} mm under the ceiling (at z = {height:.4f} m)")
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""Binding points and fixed-point scales shared by Python and GLSL, by name.

Shaders `#include "bindings"` and use `STORAGE_<NAME>`, `TEXTURE_<NAME>`, `IMAGE_<NAME>`, `UNIFORM_<NAME>` and the
scales below; Python binds through `storage(name)`, `texture_unit(name)`, `image_unit(name)`,
`uniform_block(name)`.
Numbers are unique within each group (the shaders of one pass); groups may reuse them, which
keeps every pass within OpenGL 4.3's guaranteed 8 storage-buffer bindings.
"""

from __future__ import annotations

STORAGE_GROUPS = {
    "shooting": {  # the shooting pass
        "PATCH_CORNERS": 0, "PATCH_NORMAL_AREA": 1, "PATCH_REFLECTANCE": 2, "ELEMENT_WEIGHTS": 3,
        "SHOT_ENERGY": 4, "RECORDED_VISIBILITY": 5, "PATCH_PLANE": 6, "SKY_FRACTION": 7,
    },
    "texels": {"TEXEL_POSITION": 0, "TEXEL_NORMAL": 1, "TEXEL_PLANE": 2, "TEXEL_LIGHT": 3, "TEXEL_COLUMNS": 4,
               "PATCH_PLANE": 6},  # direct light into lightmap texels (or each shot's factor: TEXEL_COLUMNS)
    "hemicube": {"DELTA_FORM_FACTORS": 1, "FORM_FACTOR_ROWS": 2},
    "item_buffer": {"LOOKUP_CUTS": 1, "LOOKUP_TABLE": 2, "LOOKUP_TWINS": 3, "LOOKUP_BINS": 4},  # bound by each draw
    "jacobi": {"FORM_FACTORS": 0, "JACOBI_EMISSION": 1, "JACOBI_REFLECTANCE": 2, "RADIOSITY_OLD": 3,
               "RADIOSITY_NEW": 4, "CONVERGENCE": 5},
    "lightmap": {"LATTICE_CORNERS": 0, "LATTICE_VALUES": 1},
    "preview": {"SURFACE_REFLECTANCE": 0, "SURFACE_EMISSION": 1},
}
TEXTURE_UNITS = {"ITEM_BUFFER": 0, "DISTANCE_MAP": 1, "RESIDUAL": 2, "HEMICUBES": 3, "LIGHTMAP": 0, "OPACITY": 4}
UNIFORM_BLOCKS = {"SHOTS": 0}  # a batch of shot records (shooting.shots)
IMAGE_UNITS = {"LIGHT": 0, "RESIDUAL": 1}

SHOT_ENERGY_ONE = 1 << 30  # the shooting pass sums hit fractions in fixed point: 2^30 = 1
FORM_FACTOR_ONE = 1 << 31  # hemi-cube delta form factors are summed as integers: 2^31 = 1

STORAGE = {name: slot for group in STORAGE_GROUPS.values() for name, slot in group.items()}
# a name shared by two groups (a buffer both passes read) has one slot: tests/core/test_gpu.py checks it


def storage(name: str) -> int:
    return STORAGE[name]


def texture_unit(name: str) -> int:
    return TEXTURE_UNITS[name]


def image_unit(name: str) -> int:
    return IMAGE_UNITS[name]


def uniform_block(name: str) -> int:
    return UNIFORM_BLOCKS[name]


def glsl() -> str:
    """The `bindings` include."""
    lines = [f"#define STORAGE_{name} {slot}" for name, slot in STORAGE.items()]
    lines += [f"#define TEXTURE_{name} {unit}" for name, unit in TEXTURE_UNITS.items()]
    lines += [f"#define IMAGE_{name} {unit}" for name, unit in IMAGE_UNITS.items()]
    lines += [f"#define UNIFORM_{name} {unit}" for name, unit in UNIFORM_BLOCKS.items()]
    lines += [f"const float SHOT_ENERGY_ONE = {float(SHOT_ENERGY_ONE)};",
              f"const float FORM_FACTOR_ONE = {float(FORM_FACTOR_ONE)};"]
    return "\n".join(lines) + "\n"

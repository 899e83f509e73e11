"""Scene files (JSON) in and out, and the bundled scenes (`cornell-box`).

Every fault a user can make is refused with a `SceneError` whose message names the surface
and the fault (docs/architecture.md, Scene file).
"""

from __future__ import annotations

import json
import math
from collections import Counter
from pathlib import Path

import numpy as np

from ..errors import SceneError
from .analysis import check_has_emitter
from .model import FaceNames, Scene, padded_corners
from .opacity import OpacityMaps
from .validate import check_polygons, check_values, vector

BUNDLED_SCENES_DIR = Path(__file__).parent / "scenes"


def _surface_entry(entry, index: int) -> tuple:
    """(name, corners (4, 3), count, reflectance, emission, object, uv (4, 2) or None, two-sided) of one entry."""
    if not isinstance(entry, dict):
        raise SceneError(f"surface #{index}: must be an object with name, vertices, reflectance, emission")
    name = entry.get("name")
    if not isinstance(name, str) or not name:
        raise SceneError(f"surface #{index}: needs a non-empty string 'name'")
    where = f"surface '{name}'"
    for key in ("vertices", "reflectance", "emission"):
        if key not in entry:
            raise SceneError(f"{where}: missing '{key}'")
    raw_vertices = entry["vertices"]
    if not isinstance(raw_vertices, list) or not 3 <= len(raw_vertices) <= 4:
        count = len(raw_vertices) if isinstance(raw_vertices, list) else "no"
        raise SceneError(f"{where}: needs 3 or 4 vertices, got {count}")
    vertices = np.stack([vector(v, 3, f"vertex {k}", where) for k, v in enumerate(raw_vertices)])
    reflectance = vector(entry["reflectance"], 3, "reflectance", where)
    emission = vector(entry["emission"], 3, "emission", where)
    uv = None
    if entry.get("uv") is not None:
        raw_uv = entry["uv"]
        if not isinstance(raw_uv, list) or len(raw_uv) != len(vertices):
            raise SceneError(f"{where}: 'uv' needs one [u, v] per vertex ({len(vertices)})")
        uv = padded_corners(np.stack([vector(t, 2, f"uv {k}", where) for k, t in enumerate(raw_uv)]))
    obj = entry.get("object", name)
    if not isinstance(obj, str) or not obj:
        raise SceneError(f"{where}: 'object' must be a non-empty string")
    two_sided = entry.get("two_sided", False)
    if not isinstance(two_sided, bool):
        raise SceneError(f"{where}: 'two_sided' must be true or false, got {two_sided!r}")
    return name, padded_corners(vertices), len(vertices), reflectance, emission, obj, uv, two_sided


def scene_from_dict(data: dict, require_emitter: bool = True) -> Scene:
    """A validated Scene from a scene-file dict."""
    if not isinstance(data, dict) or not isinstance(data.get("surfaces"), list):
        raise SceneError("scene: expected a JSON object with a 'surfaces' list")
    if not data["surfaces"]:
        raise SceneError("scene: the 'surfaces' list is empty")
    entries = [_surface_entry(entry, k) for k, entry in enumerate(data["surfaces"])]
    names, corners, counts, reflectance, emission, objects, uvs, two_sided = (list(column) for column in zip(*entries))
    duplicates = sorted(name for name, count in Counter(names).items() if count > 1)
    if duplicates:
        raise SceneError(f"surface '{duplicates[0]}': the name is used by more than one surface")
    corners, counts = np.stack(corners), np.array(counts, dtype=np.int64)
    reflectance, emission = np.stack(reflectance), np.stack(emission)
    check_polygons(corners, counts, names)
    check_values(names, reflectance, emission)
    object_names = list(dict.fromkeys(objects))
    object_of = {name: k for k, name in enumerate(object_names)}
    has_uv = np.array([uv is not None for uv in uvs], dtype=bool)
    scene = Scene(names=names, corners=corners, corner_count=counts, reflectance=reflectance, emission=emission,
                  object_index=np.array([object_of[o] for o in objects], dtype=np.int64), object_names=object_names,
                  uv=np.stack([uv if uv is not None else np.zeros((4, 2)) for uv in uvs]), has_uv=has_uv,
                  two_sided=np.array(two_sided, dtype=bool),
                  extras={k: v for k, v in data.items() if k != "surfaces"})
    if require_emitter:
        check_has_emitter(scene)
    return scene


def bundled_scene_names() -> list[str]:
    return sorted(p.stem for p in BUNDLED_SCENES_DIR.glob("*.json"))


def resolve_scene_path(path_or_name: str | Path) -> Path:
    path = Path(path_or_name)
    if path.suffix == "" and not path.exists():
        bundled = BUNDLED_SCENES_DIR / f"{path_or_name}.json"
        if bundled.exists():
            return bundled
        raise SceneError(
            f"scene: '{path_or_name}' is neither a file nor a bundled scene"
            f" ({', '.join(bundled_scene_names())})"
        )
    if not path.exists():
        raise SceneError(f"scene: file '{path}' does not exist")
    return path


def load_scene(path_or_name: str | Path, require_emitter: bool = True) -> Scene:
    """Load a scene file (JSON, or the arrays of `save_scene` in an .npz), or a bundled scene by
    name (e.g. 'cornell-box')."""
    path = resolve_scene_path(path_or_name)
    if path.suffix == ".npz":
        return scene_from_arrays(path, require_emitter)
    try:
        data = json.loads(path.read_text(), parse_constant=lambda c: math.nan)
    except json.JSONDecodeError as error:
        raise SceneError(f"scene: '{path}' is not valid JSON ({error})") from None
    except OSError as error:
        raise SceneError(f"scene: cannot read '{path}' ({error.strerror})") from None
    return scene_from_dict(data, require_emitter=require_emitter)


def save_scene(scene: Scene, path: str | Path) -> None:
    """The scene file: JSON, or its arrays when `path` ends in .npz (what the solver process gets:
    a large mesh's arrays are a fraction of its JSON's size and read in a fraction of its time)."""
    path = Path(path)
    if path.suffix == ".npz":
        save_scene_arrays(scene, path)
    else:
        path.write_text(json.dumps(scene.to_dict(), indent=1))


ARRAY_FIELDS = ("corners", "corner_count", "reflectance", "emission", "object_index", "uv", "has_uv", "two_sided")


def save_scene_arrays(scene: Scene, path: Path) -> None:
    arrays = {name: getattr(scene, name) for name in ARRAY_FIELDS}
    arrays["object_names"] = np.array(scene.object_names, dtype=str)
    arrays["extras"] = np.array(json.dumps(scene.extras))
    if not isinstance(scene.names, FaceNames):
        arrays["names"] = np.array(list(scene.names), dtype=str)
    if scene.opacity is not None:
        arrays.update(scene.opacity.arrays())
    with open(path, "wb") as file:
        np.savez(file, **arrays)


def scene_from_arrays(path: Path, require_emitter: bool = True) -> Scene:
    """A validated Scene from `save_scene`'s arrays."""
    try:
        with np.load(path, allow_pickle=False) as data:
            arrays = {name: data[name] for name in data.files}
    except (OSError, ValueError) as error:
        raise SceneError(f"scene: cannot read '{path}' ({error})") from None
    missing = [name for name in ARRAY_FIELDS + ("object_names", "extras") if name not in arrays]
    if missing:
        raise SceneError(f"scene: '{path}' lacks the array '{missing[0]}'")
    object_names = [str(name) for name in arrays["object_names"]]
    object_index = arrays["object_index"].astype(np.int64)
    if len(object_index) and (object_index.min() < 0 or object_index.max() >= len(object_names)):
        raise SceneError(f"scene: '{path}' has surfaces of objects it does not name")
    names = [str(name) for name in arrays["names"]] if "names" in arrays else FaceNames(object_names, object_index)
    corners, counts = arrays["corners"].astype(np.float64), arrays["corner_count"].astype(np.int64)
    reflectance, emission = arrays["reflectance"].astype(np.float64), arrays["emission"].astype(np.float64)
    check_polygons(corners, counts, names)
    check_values(names, reflectance, emission)
    scene = Scene(names=names, corners=corners, corner_count=counts, reflectance=reflectance, emission=emission,
                  object_index=object_index, object_names=object_names, uv=arrays["uv"].astype(np.float64),
                  has_uv=arrays["has_uv"].astype(bool), two_sided=arrays["two_sided"].astype(bool),
                  extras=json.loads(str(arrays["extras"])), opacity=OpacityMaps.from_arrays(arrays))
    if require_emitter:
        check_has_emitter(scene)
    return scene

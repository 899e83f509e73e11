"""What the Blender side and the solver process exchange: a job folder, images as .npz files and
one JSON object per line on the pipe.

Job folder: scene.npz (the scene file's arrays, `core.save_scene`), materials.npz (the textured
objects' albedo and emission maps, as Cycles baked them), job.json (settings, the objects that get
lightmaps, the preview interval); the child adds result.npz and preview-N.npz.
Messages (child -> parent): {"kind": KIND, ...} with KIND one of
  ready     a spare's first word: its imports are done and its context open (it sends no
            other until its job folder comes)
  alive     a heartbeat, every HEARTBEAT seconds, from a thread of its own
  progress  fraction, message, eta (seconds the solver expects to need, or null)
  stage     name ("lightmaps": the solve is done, the images are being laid out)
  preview   file (an .npz of the images so far, the ambient term included)
  result    file (.npz), report (Report.to_dict()), summary (Report.summary_line())
  error     user (a fault the user can fix, else a bug or a crash), message (one line)
Parent -> child: a spare (a child started ahead, with `-` for its job folder) reads its folder as
one JSON string and a newline on stdin; nothing else. Its stdin closing (the parent is gone) ends
the child at once, and a cancel kills it (it writes nothing outside its own folder).
"""

from __future__ import annotations

import json
from dataclasses import asdict
from pathlib import Path

import numpy as np

from .. import core

SCENE_FILE = "scene.npz"
JOB_FILE = "job.json"
MATERIALS_FILE = "materials.npz"
RESULT_FILE = "result.npz"
HEARTBEAT = 1.0  # seconds between "alive" messages


def write_job(directory: Path, scene, solve: core.SolveSettings, lightmaps: core.LightmapSettings,
              objects: list[str], preview_interval: float | None) -> None:
    core.save_scene(scene, directory / SCENE_FILE)
    maps = scene.material_maps
    save_images(directory / MATERIALS_FILE, {f"{kind}:{name}": getattr(maps[name], kind)
                                             for name in maps for kind in ("albedo", "emission")})
    job = {"solve": solve.as_dict(), "lightmaps": asdict(lightmaps), "objects": list(objects),
           "preview_interval": preview_interval}
    (directory / JOB_FILE).write_text(json.dumps(job))


def read_job(directory: Path):
    """(scene, SolveSettings, LightmapSettings, objects, preview interval or None)."""
    job = json.loads((directory / JOB_FILE).read_text())
    scene = core.load_scene(str(directory / SCENE_FILE), require_emitter=False)
    images = load_images(directory / MATERIALS_FILE)
    names = dict.fromkeys(key.split(":", 1)[1] for key in images)
    scene.material_maps = {name: core.MaterialMap(albedo=images[f"albedo:{name}"], emission=images[f"emission:{name}"])
                           for name in names}
    return (scene, core.SolveSettings(**job["solve"]), core.LightmapSettings(**job["lightmaps"]), job["objects"],
            job["preview_interval"])


def save_images(path: Path, images: dict) -> None:
    """object name -> float32 RGBA image, written whole before it is renamed into place (a reader
    never sees half a file)."""
    names = list(images)
    partial = path.with_name(path.name + ".partial")
    with open(partial, "wb") as file:
        np.savez(file, names=np.array(names, dtype=str), **{f"image{k}": images[n] for k, n in enumerate(names)})
    partial.replace(path)


def load_images(path: Path) -> dict:
    with np.load(path, allow_pickle=False) as data:
        return {str(name): data[f"image{k}"] for k, name in enumerate(data["names"])}


def encode(kind: str, **fields) -> str:
    return json.dumps({"kind": kind, **fields}) + "\n"


def decode(line: str) -> dict | None:
    """A message, or None for a line that is not one (the child's stdout carries nothing else, but a
    crash may cut a line short)."""
    try:
        message = json.loads(line)
    except ValueError:
        return None
    return message if isinstance(message, dict) and "kind" in message else None

"""GLSL sources from `shaders/`: one file per stage, shared snippets in `shaders/include/`
(`#include "name"`), compile-time constants as `#define`s after the `#version` line."""

from __future__ import annotations

import functools
from pathlib import Path

from . import bindings

SHADERS_DIR = Path(__file__).resolve().parents[3] / "shaders"
INCLUDE_DIR = SHADERS_DIR / "include"
STAGE_SUFFIXES = (".vert", ".geom", ".frag", ".comp")
loaded: set[str] = set()  # the stage files this process has read: what a test run compiled


def stage_files() -> list[str]:
    """Every stage file in `shaders/`."""
    return sorted(path.name for path in SHADERS_DIR.iterdir() if path.suffix in STAGE_SUFFIXES)


@functools.lru_cache(maxsize=None)
def shader_source(name: str) -> str:
    path = SHADERS_DIR / name
    if not path.is_file():
        raise FileNotFoundError(f"shader '{name}' not found in {SHADERS_DIR}; reinstall the add-on")
    loaded.add(name)
    return path.read_text()


def with_defines(source: str, defines: dict | None) -> str:
    """Insert `#define NAME value` lines right after the `#version` line."""
    if not defines:
        return source
    head, _, rest = source.partition("\n")
    lines = "".join(f"#define {key} {value}\n" for key, value in defines.items())
    return f"{head}\n{lines}{rest}"


def includes() -> dict[str, str]:
    """Every `#include` a shader may use: the files of shaders/include and the generated bindings."""
    sources = {path.stem: path.read_text() for path in sorted(INCLUDE_DIR.glob("*.glsl"))}
    sources["bindings"] = bindings.glsl()
    return sources

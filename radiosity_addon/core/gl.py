"""The one place that creates OpenGL contexts and loads GLSL from `shaders/`.

Contexts are moderngl standalone contexts (EGL, OpenGL 4.3+: compute and
geometry shaders). Inside Blender's UI the main thread owns Blender's own
context, so callers create, use and release ours on one worker thread.
"""

from __future__ import annotations

import contextlib
import functools
from pathlib import Path

SHADERS_DIR = Path(__file__).resolve().parents[2] / "shaders"
REQUIRED_GL = 430
MISSING_LIBRARIES_HINT = (
    "install OpenGL/EGL (Debian/Ubuntu: sudo apt-get install libegl1 libegl-mesa0 libgl1-mesa-dri)"
)


class GLUnavailable(RuntimeError):
    """No usable OpenGL 4.3 context: the message says what to install."""


def create_context():
    """A standalone OpenGL 4.3+ context (EGL first, then the platform default)."""
    try:
        import moderngl
    except ImportError as error:
        raise GLUnavailable(f"the moderngl package is missing ({error}); reinstall the add-on") from None
    errors = []
    for backend in ("egl", None):
        try:
            kwargs = {"standalone": True, "require": REQUIRED_GL}
            if backend:
                kwargs["backend"] = backend
            return moderngl.create_context(**kwargs)
        except Exception as error:  # moderngl/glcontext raise plain Exceptions
            errors.append(f"{backend or 'default'}: {str(error).splitlines()[0] if str(error) else type(error).__name__}")
    raise GLUnavailable(
        f"cannot create an OpenGL {REQUIRED_GL // 100}.{REQUIRED_GL % 100 // 10} context"
        f" ({'; '.join(errors)}); {MISSING_LIBRARIES_HINT}"
    )


@contextlib.contextmanager
def gl_context(ctx=None):
    """Yield `ctx` if given, else a fresh context released on exit."""
    if ctx is not None:
        yield ctx
        return
    own = create_context()
    try:
        yield own
    finally:
        own.release()


@functools.lru_cache(maxsize=None)
def shader_source(name: str) -> str:
    path = SHADERS_DIR / name
    if not path.exists():
        raise FileNotFoundError(f"shader '{name}' not found in {SHADERS_DIR}")
    return path.read_text()


def with_defines(source: str, defines: dict | None) -> str:
    """Insert `#define NAME value` lines right after the `#version` line."""
    if not defines:
        return source
    head, _, rest = source.partition("\n")
    lines = "".join(f"#define {key} {value}\n" for key, value in defines.items())
    return f"{head}\n{lines}{rest}"


def program(ctx, vertex: str, fragment: str | None = None, geometry: str | None = None,
            defines: dict | None = None, varyings=()):
    """Link a program from shader file names in `shaders/`."""
    load = lambda name: with_defines(shader_source(name), defines) if name else None  # noqa: E731
    return ctx.program(
        vertex_shader=load(vertex),
        fragment_shader=load(fragment),
        geometry_shader=load(geometry),
        varyings=varyings,
    )


def compute(ctx, name: str, defines: dict | None = None):
    """A compute shader from `shaders/name`."""
    return ctx.compute_shader(with_defines(shader_source(name), defines))


def groups(count: int, local_size: int) -> int:
    """Work groups needed to cover `count` invocations."""
    return max(1, -(-count // local_size))

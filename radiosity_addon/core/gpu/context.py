"""The one place that creates OpenGL contexts: moderngl standalone contexts (EGL first, then
the platform default), OpenGL 4.3+ for compute and geometry shaders.

Inside Blender's UI the main thread owns Blender's own context, so a caller creates, uses and
releases ours on one thread of its own (or in a process of its own).
"""

from __future__ import annotations

from ..errors import GLUnavailable

REQUIRED_GL = 430
MAX_WORK_GROUPS = 65535  # work groups per dispatch dimension that every OpenGL 4.3 guarantees
MISSING_LIBRARIES_HINT = (
    "install OpenGL/EGL (Debian/Ubuntu: sudo apt-get install libegl1 libegl-mesa0 libgl1-mesa-dri)"
)


def version_text(code: int) -> str:
    return f"{code // 100}.{code % 100 // 10}"


def create_context():
    """A standalone OpenGL 4.3+ moderngl context; GLUnavailable (one line) when there is none: what
    was found (an older OpenGL, or none at all) and what to do."""
    try:
        import moderngl
    except ImportError as error:
        raise GLUnavailable(f"the moderngl package is missing ({error}); reinstall the add-on") from None
    errors, older = [], []
    for backend in ("egl", None):
        try:
            context = moderngl.create_context(standalone=True, **({"backend": backend} if backend else {}))
        except Exception as error:  # moderngl/glcontext raise plain Exceptions
            errors.append(f"{backend or 'default'}: {str(error).splitlines()[0] if str(error) else type(error).__name__}")
            continue
        if context.version_code >= REQUIRED_GL:
            return context
        older.append(f"OpenGL {version_text(context.version_code)} ({context.info.get('GL_RENDERER', 'unknown')})")
        context.release()
    if older:  # a driver, but too old a one: no library to install
        raise GLUnavailable(
            f"this machine offers {older[0]}; the bake needs OpenGL {version_text(REQUIRED_GL)} (compute shaders):"
            " update the graphics driver, or bake on a machine with OpenGL 4.3 (macOS offers 4.1, which is not"
            " supported yet)")
    raise GLUnavailable(f"cannot create an OpenGL {version_text(REQUIRED_GL)} context ({'; '.join(errors)});"
                        f" {MISSING_LIBRARIES_HINT}")


def work_groups(count: int, local_size: int) -> int:
    """Work groups needed to cover `count` invocations."""
    return max(1, -(-count // local_size))

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


def create_context():
    """A standalone OpenGL 4.3+ moderngl context; GLUnavailable (one line) when there is none."""
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


def work_groups(count: int, local_size: int) -> int:
    """Work groups needed to cover `count` invocations."""
    return max(1, -(-count // local_size))

"""The errors a user can cause, each with a one-line message that says what to do.

Every caller (command line, Blender operator, benchmark) reports an error of `USER_ERRORS`
as its message alone; anything else is a bug and keeps its traceback.
"""

from __future__ import annotations


class SceneError(ValueError):
    """A scene the user gave cannot be solved; the message names the surface and the fault."""


class SolveError(RuntimeError):
    """A solve that cannot proceed (bad settings, memory guard, no convergence)."""


class SolveCancelled(RuntimeError):
    """The user cancelled the solve."""


class GLUnavailable(RuntimeError):
    """No usable OpenGL 4.3 context: the message says what to install."""


USER_ERRORS = (SceneError, SolveError, SolveCancelled, GLUnavailable, FileNotFoundError)

"""OpenGL's own reports (KHR_debug) as failures: with RADIOSITY_GL_DEBUG=1 in the environment (the
tests set it), every context a `GPU` holds logs what the driver reports, and the errors and
undefined or deprecated behaviour it logged are read back with `drain` (a `GPU` raises them when it closes).

Read by polling glGetDebugMessageLog, not through a callback: a callback from the driver's thread
into Python would need the interpreter's lock inside any GL call."""

from __future__ import annotations

import ctypes
import ctypes.util
import os
import weakref

ENVIRONMENT_SWITCH = "RADIOSITY_GL_DEBUG"
GL_DEBUG_OUTPUT = 0x92E0
GL_DEBUG_OUTPUT_SYNCHRONOUS = 0x8242  # each message logged inside the call that caused it
PROBLEM_TYPES = {0x824C: "error", 0x824D: "deprecated behaviour", 0x824E: "undefined behaviour"}
SEVERITIES = {0x9146: "high", 0x9147: "medium", 0x9148: "low", 0x826B: "notification"}
MESSAGES_PER_READ = 64
TEXT_BYTES = 1 << 16



class GLReportedProblem(RuntimeError):
    """The driver logged an OpenGL error or undefined behaviour (only with RADIOSITY_GL_DEBUG=1)."""


_watched: "weakref.WeakSet" = weakref.WeakSet()  # contexts logging, for `watched_contexts`
_read_log = None  # glGetDebugMessageLog, once looked up


def requested() -> bool:
    return os.environ.get(ENVIRONMENT_SWITCH, "") not in ("", "0")


def _message_log_function():
    """glGetDebugMessageLog through EGL (the backend every context here is tried on first), or None
    where EGL has no such entry point."""
    global _read_log
    if _read_log is None:
        name = ctypes.util.find_library("EGL")
        if not name:
            return None
        egl = ctypes.CDLL(name)
        egl.eglGetProcAddress.restype = ctypes.c_void_p
        egl.eglGetProcAddress.argtypes = [ctypes.c_char_p]
        address = egl.eglGetProcAddress(b"glGetDebugMessageLog")
        if not address:
            return None
        uint_array = ctypes.POINTER(ctypes.c_uint)
        _read_log = ctypes.CFUNCTYPE(ctypes.c_uint, ctypes.c_uint, ctypes.c_int, uint_array, uint_array,
                                     uint_array, uint_array, ctypes.POINTER(ctypes.c_int),
                                     ctypes.c_char_p)(address)
    return _read_log


def watch(ctx) -> bool:
    """Make the current context `ctx` log the driver's messages (when RADIOSITY_GL_DEBUG asks for
    it and the context has KHR_debug); whether it does."""
    if not requested() or "GL_KHR_debug" not in ctx.extensions or _message_log_function() is None:
        return False
    ctx.enable_direct(GL_DEBUG_OUTPUT)
    ctx.enable_direct(GL_DEBUG_OUTPUT_SYNCHRONOUS)
    _watched.add(ctx)
    return True


def drain(ctx) -> list[str]:
    """The problems the current context `ctx` logged since the last read, one line each; the log
    is emptied (notifications, performance and portability notes are read and dropped)."""
    if ctx not in _watched:
        return []
    read_log = _message_log_function()
    count = MESSAGES_PER_READ
    sources, types, ids, severities = ((ctypes.c_uint * count)() for _ in range(4))
    lengths = (ctypes.c_int * count)()
    text = ctypes.create_string_buffer(TEXT_BYTES)
    problems = []
    while True:
        read = read_log(count, TEXT_BYTES, sources, types, ids, severities, lengths, text)
        offset = 0
        for k in range(read):
            message = text.raw[offset:offset + lengths[k]].rstrip(b"\0").decode(errors="replace")
            offset += lengths[k]
            kind = PROBLEM_TYPES.get(types[k])
            if kind:
                problems.append(f"OpenGL {kind} ({SEVERITIES.get(severities[k], hex(severities[k]))}): {message}")
        if read < count:
            return problems


def watched_contexts() -> list:
    """The contexts logging now."""
    return list(_watched)


def forget(ctx) -> None:
    _watched.discard(ctx)

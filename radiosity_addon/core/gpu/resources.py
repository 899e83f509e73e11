"""The owner of every GL object: a `GPU` (one context and its program cache) hands out
`Resources` scopes; a scope releases all it made when it closes, on success, on cancel and on
any exception, so no stage keeps a release list of its own.

A scope also makes its context current while it is open (and the previous one current again
after), so several contexts in one thread — a caller's and one of its own — never mix.

Render targets a pass clears before every use (visibility atlases and maps: up to 100 MB each)
are `scratch`: a closing scope hands them back to its GPU, and the next scope asking for the same
size takes them instead of a fresh allocation, which llvmpipe zero-fills page by page (~0.14 s
for a 4096 x 3072 atlas and its depth, once per probe round and per texel pass before this pool).

What several passes of one job draw alike (the surfaces' visibility from the same emitter pieces,
seen by every refinement round, the direct light and the lightmaps) is `kept`: made once in a
scope of the GPU's own, kept until the GPU closes (or the least recently used of MAX_KEPT goes)."""

from __future__ import annotations

import contextlib
import re
import threading

from . import debug
from .context import create_context
from .shaders import includes, shader_source, with_defines


CLIP_DISTANCE0 = 0x3000  # GL_CLIP_DISTANCE0 (moderngl has no name for it)
MAX_SPARE_BYTES = 512 << 20  # scratch targets kept between scopes: two texel-pass atlases and their depth
MAX_KEPT = 4  # objects `kept` between passes (a texel pass's atlas and its depth: ~50 MB each)
BYTES_PER_TEXEL = {"f1": 1, "u1": 1, "i1": 1, "f2": 2, "u2": 2, "i2": 2, "f4": 4, "u4": 4, "i4": 4}


def scratch_bytes(key: tuple) -> int:
    """Memory of a scratch target ("texture" | "depth", (w, h), components, dtype)."""
    _, (width, height), components, dtype = key
    return width * height * components * BYTES_PER_TEXEL[dtype]


def clip_distances_written(source: str | None) -> int:
    """How many gl_ClipDistance values a vertex or geometry shader's source declares it writes."""
    match = re.search(r"out\s+float\s+gl_ClipDistance\s*\[\s*(\d+)\s*\]", source or "")
    return int(match.group(1)) if match else 0


@contextlib.contextmanager
def _clip_distances(vao):
    count = (vao.program.extra or {}).get("clip_distances", 0)
    for k in range(count):
        vao.ctx.enable_direct(CLIP_DISTANCE0 + k)
    try:
        yield
    finally:
        for k in range(count):
            vao.ctx.disable_direct(CLIP_DISTANCE0 + k)


def render_indirect(vao, commands, count: int) -> None:
    """`vao.render_indirect` of `count` commands in buffer `commands` (one multi-draw call), with the
    clip distances its program writes enabled, as `render`."""
    with _clip_distances(vao):
        vao.render_indirect(commands, count=count)


def render(vao, **kwargs) -> None:
    """`vao.render(**kwargs)` with the clip distances its program writes enabled, and disabled
    after. A conformant driver (NVIDIA's, and the GL spec) clips only against enabled distances
    and ignores the rest; Mesa's llvmpipe clips against every distance written, enabled or not,
    so a missing enable passes every test here and draws each hemi-cube face over the whole atlas
    on a real GPU (seen on an NVIDIA H200: black lightmaps)."""
    with _clip_distances(vao):
        vao.render(**kwargs)


_active = threading.local()  # per thread: the contexts made current by `active`, innermost last


@contextlib.contextmanager
def active(ctx):
    """Make `ctx` current for the block, and the one that was current before again after it.
    (moderngl's own `with ctx:` leaves no context current on exit, which would strand a caller's.)"""
    stack = _active.__dict__.setdefault("stack", [])
    if not stack or stack[-1] is not ctx:
        ctx.mglo.__enter__()
    stack.append(ctx)
    try:
        yield ctx
    finally:
        stack.pop()
        if stack and stack[-1] is not ctx:
            stack[-1].mglo.__enter__()


class GPU:
    """An OpenGL context with its compiled programs. Programs are cached per context (keyed by
    shader files and defines) and released with it; everything else lives in `resources()`."""

    def __init__(self, ctx=None):
        self.ctx = ctx if ctx is not None else create_context()
        self._owns_context = ctx is None
        self._programs: dict[tuple, object] = {}
        self._spares: dict[tuple, list] = {}  # scratch targets no scope holds, by (kind, size, format)
        self._kept: dict[tuple, tuple] = {}  # key -> (its own scope, the object), least recently used first
        for name, source in includes().items():
            self.ctx.includes[name] = source
        with active(self.ctx):
            debug.watch(self.ctx)
            self._no_framebuffer = self.ctx.detect_framebuffer(0)  # binding 0 is always valid

    def rest_framebuffer(self) -> None:
        """Bind no framebuffer (0): moderngl binds its last-used one again after making the next,
        which must never be a released one (GL_INVALID_OPERATION)."""
        self._no_framebuffer.use()

    def program(self, vertex: str, fragment: str | None = None, geometry: str | None = None,
                defines: dict | None = None):
        """A linked program from shader files in `shaders/` (cached)."""
        key = ("program", vertex, fragment, geometry, tuple(sorted((defines or {}).items())))
        if key not in self._programs:
            load = lambda name: with_defines(shader_source(name), defines) if name else None  # noqa: E731
            program = self.ctx.program(vertex_shader=load(vertex), fragment_shader=load(fragment),
                                       geometry_shader=load(geometry))
            # the stage before rasterization writes the clip distances that `render` enables
            program.extra = {"clip_distances": clip_distances_written(load(geometry or vertex))}
            self._programs[key] = program
        return self._programs[key]

    def compute(self, name: str, defines: dict | None = None):
        """A compute shader from `shaders/name` (cached)."""
        key = ("compute", name, tuple(sorted((defines or {}).items())))
        if key not in self._programs:
            self._programs[key] = self.ctx.compute_shader(with_defines(shader_source(name), defines))
        return self._programs[key]

    @property
    def program_count(self) -> int:
        """Programs compiled on this context so far."""
        return len(self._programs)

    def resources(self) -> "Resources":
        return Resources(self)

    def kept(self, key: tuple, make):
        """The object `make(resources)` made for `key`, made on the first call and kept, with all
        it made in `resources`, for the later calls with that key until the GPU closes (at most
        MAX_KEPT keys: the least recently used is released first)."""
        if key in self._kept:
            self._kept[key] = self._kept.pop(key)  # now the most recently used
            return self._kept[key][1]
        while len(self._kept) >= MAX_KEPT:
            scope, _ = self._kept.pop(next(iter(self._kept)))
            scope.release()
        scope = Resources(self)
        try:
            obj = make(scope)
        except BaseException:
            scope.release()
            raise
        self._kept[key] = (scope, obj)
        return obj

    @property
    def kept_count(self) -> int:
        return len(self._kept)

    @property
    def spares(self) -> list:
        """The scratch targets kept for the next scope."""
        return [obj for spares in self._spares.values() for obj in spares]

    @property
    def spare_bytes(self) -> int:
        """Memory of the scratch targets kept for the next scope."""
        return sum(scratch_bytes(key) * len(spares) for key, spares in self._spares.items())

    def take_spare(self, key: tuple):
        """A scratch target of `key` a closed scope gave back, or None."""
        spares = self._spares.get(key)
        return spares.pop() if spares else None

    def give_back(self, key: tuple, obj) -> None:
        """Keep a scratch target for the next scope, or release it when the pool is full."""
        if self.spare_bytes + scratch_bytes(key) > MAX_SPARE_BYTES:
            obj.release()
            return
        self._spares.setdefault(key, []).append(obj)

    def release_targets(self) -> None:
        """Release what is kept between scopes (`kept` objects, pooled scratch targets) and keep
        only the compiled programs: a context warmed by one job holds no memory for the next."""
        with active(self.ctx):
            self.rest_framebuffer()
            for scope, _ in reversed(list(self._kept.values())):
                scope.release()
            self._kept.clear()
            for spares in self._spares.values():
                for obj in spares:
                    obj.release()
            self._spares.clear()

    def close(self, report_problems: bool = True) -> None:
        """Release everything; then raise GLReportedProblem if the driver reported errors or
        undefined behaviour on this context (only where RADIOSITY_GL_DEBUG asked it to log)."""
        self.release_targets()
        with active(self.ctx):
            for program in self._programs.values():
                program.release()
            self._programs.clear()
            problems = debug.drain(self.ctx)
        debug.forget(self.ctx)
        if self._owns_context:
            self.ctx.release()
        if problems and report_problems:
            raise debug.GLReportedProblem("; ".join(problems))

    def __enter__(self) -> "GPU":
        return self

    def __exit__(self, exc_type, *exc) -> None:
        self.close(report_problems=exc_type is None)


@contextlib.contextmanager
def open_gpu(gpu: GPU | None = None):
    """Yield `gpu` if given, else a fresh one (its own context) closed on exit."""
    if gpu is not None:
        with active(gpu.ctx):
            yield gpu
        return
    with GPU() as own, active(own.ctx):
        yield own


class Resources:
    """GL objects of one scope (a solve, a bake, a pass), released together, newest first."""

    def __init__(self, gpu: GPU):
        self.gpu = gpu
        self.ctx = gpu.ctx
        self._objects: list = []
        self._scratch: dict[int, tuple] = {}  # id(obj) -> its key, for the scratch targets this scope holds
        self._active = None

    def adopt(self, obj):
        self._objects.append(obj)
        return obj

    def buffer(self, data: bytes | None = None, reserve: int = 0):
        return self.adopt(self.ctx.buffer(data, reserve=reserve) if data is not None
                          else self.ctx.buffer(reserve=max(reserve, 4)))

    def texture(self, size, components: int, data: bytes | None = None, dtype: str = "f1"):
        return self.adopt(self.ctx.texture(size, components, data, dtype=dtype))

    def depth_renderbuffer(self, size):
        return self.adopt(self.ctx.depth_renderbuffer(size))

    def scratch_texture(self, size, components: int, dtype: str = "f1"):
        """A texture whose contents are undefined (the caller clears it before each use), from
        the GPU's pool when one of that size was given back; nearest filtering."""
        texture = self._scratch_target(("texture", tuple(size), components, dtype),
                                       lambda: self.ctx.texture(size, components, dtype=dtype))
        texture.filter = (self.ctx.NEAREST, self.ctx.NEAREST)
        return texture

    def scratch_depth(self, size):
        """A depth renderbuffer whose contents are undefined (cleared before each use), pooled."""
        return self._scratch_target(("depth", tuple(size), 1, "f4"), lambda: self.ctx.depth_renderbuffer(size))

    def _scratch_target(self, key: tuple, make):
        obj = self.gpu.take_spare(key)
        if obj is None:
            obj = make()
        self._scratch[id(obj)] = key
        return self.adopt(obj)

    def framebuffer(self, color_attachments, depth_attachment=None):
        return self.adopt(self.ctx.framebuffer(color_attachments, depth_attachment))

    def value_and_id_target(self, size):
        """An off-screen target, bound with its viewport and cleared: an RGBA float value and an
        integer id per pixel, depth-tested (what the lightmap rasterizer and the preview draw);
        returns the framebuffer (attachment 0: values, 1: ids)."""
        fbo = self.framebuffer([self.texture(size, 4, dtype="f4"), self.texture(size, 1, dtype="i4")],
                               self.depth_renderbuffer(size))
        fbo.use()
        fbo.viewport = (0, 0, *size)
        fbo.clear(depth=1.0)
        return fbo

    def vertex_array(self, program, content, index_buffer=None, index_element_size: int = 4):
        return self.adopt(self.ctx.vertex_array(program, content, index_buffer=index_buffer,
                                                index_element_size=index_element_size))

    def release(self) -> None:
        if any(type(obj).__name__ == "Framebuffer" for obj in self._objects):
            self.gpu.rest_framebuffer()
        while self._objects:
            obj = self._objects.pop()
            key = self._scratch.pop(id(obj), None)
            if key is None:
                obj.release()
            else:
                self.gpu.give_back(key, obj)

    def __enter__(self) -> "Resources":
        self._active = active(self.ctx)
        self._active.__enter__()
        return self

    def __exit__(self, *exc) -> None:
        try:
            self.release()
        finally:
            self._active.__exit__(*exc)

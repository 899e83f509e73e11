"""The bake's background half: the solve in a process of its own (`solver_process`), watched here.

bpy-free. A solve on a thread of Blender's process froze the UI (the thread holds Python's global
lock for seconds) and a crash of the OpenGL driver would have taken Blender with it. So the child
runs in Blender's own Python, started with the extension's path and Blender's `sys.path` (numpy,
and moderngl from the extension's wheels). A reader thread, idle on the pipe, turns the child's
messages into state; the main thread only polls it (the modal timer, or a script's wait loop),
so it never waits on the child. The images come back as files in a temporary folder.

Every bake but the first of a session takes a spare: a child started when the previous bake ended,
its imports done, its OpenGL context open and warmed by a small solve (its programs compiled),
waiting for a job folder (solver_process/child.py).
One spare at most; it ends on its own after SPARE_IDLE seconds without a bake, with Blender, and
when the add-on is disabled. A bake takes it only if it was started with the command this one
would use (the same interpreter, path and bootstrap), else it ends it and starts a child of its own.
The bake is over when the result comes: the child's release of its context is not waited for.
"""

from __future__ import annotations

import json
import shutil
import signal
import subprocess
import sys
import tempfile
import threading
import time
from dataclasses import dataclass
from pathlib import Path

from ..core import LightmapSettings, Scene, SolveCancelled, SolveSettings
from ..solver_process import protocol
from ..solver_process.child import SPARE
from .errors import BakeError
from .progress import BakeClock

SILENCE_LIMIT = 60.0  # seconds without a word from the child, heartbeats included: it hangs
WAIT_STEP = 0.1  # seconds `wait` sleeps at most between polls when no message comes
NICENESS = 10  # the child's priority below Blender's, so the UI gets the CPU first
# run by `python -I -c`: lower its priority before anything else (its imports are work too), the
# parent's path, then the child's main (argv: sys.path as JSON, the job folder)
BOOTSTRAP = (f"import os, sys, json; hasattr(os, 'nice') and os.nice({NICENESS}); "
             "sys.path[:0] = json.loads(sys.argv[1]); "
             "from radiosity_addon.solver_process.child import main; sys.exit(main(sys.argv[2]))")
# Windows: no console window, and a priority below Blender's (it has no os.nice)
WINDOWS_FLAGS = getattr(subprocess, "CREATE_NO_WINDOW", 0) | getattr(subprocess, "BELOW_NORMAL_PRIORITY_CLASS", 0)


def extension_root() -> Path:
    """The folder holding the `radiosity_addon` package (the extension's, or the source tree)."""
    return Path(__file__).resolve().parents[2]


def child_command(directory: Path | None) -> list[str]:
    """Blender's Python (sys.executable in Blender 2.91+; the bpy module's interpreter otherwise),
    isolated from the user's PYTHON* variables, with this process's import path; directory None: a
    spare's (it reads its job folder from stdin)."""
    path = [str(extension_root())] + [str(Path(p).resolve()) for p in sys.path if p]
    return [sys.executable, "-I", "-c", BOOTSTRAP, json.dumps(path), SPARE if directory is None else str(directory)]


def launch(command: list[str]) -> subprocess.Popen:
    return subprocess.Popen(command, stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True, encoding="utf-8",
                            creationflags=WINDOWS_FLAGS)


def end_process(process: subprocess.Popen) -> None:
    """Kill `process` if it still runs and reap it (Windows removes no file of a running process)."""
    if process.poll() is None:
        process.kill()
    try:
        process.stdin.close()
        process.wait(5.0)
    except (OSError, subprocess.TimeoutExpired):
        pass


def reap(process: subprocess.Popen | None, directory: Path | None) -> None:
    """End and reap `process` (`end_process`), then remove `directory`."""
    if process is not None:
        end_process(process)
    if directory is not None:
        shutil.rmtree(directory, ignore_errors=True)


@dataclass
class Spare:
    command: list[str]  # what started it
    process: subprocess.Popen
    waiting: threading.Thread  # reads its first line, "ready", then ends: the rest is the bake's


_spare: Spare | None = None
_keep_spare = True


def keep_spare(enabled: bool) -> None:
    """Whether a bake's end starts a spare for the next (the command line's single bake: no)."""
    global _keep_spare
    _keep_spare = enabled
    if not enabled:
        end_spare()


def start_spare() -> None:
    """Start a spare for the next bake, unless one runs already."""
    global _spare
    if not _keep_spare or (_spare is not None and _spare.process.poll() is None):
        return
    command = child_command(None)
    try:
        process = launch(command)
    except OSError:  # no spare then: the next bake starts its own child and says why it cannot
        _spare = None
        return
    waiting = threading.Thread(target=process.stdout.readline, name="radiosity-spare-ready", daemon=True)
    waiting.start()
    _spare = Spare(command, process, waiting)


def wait_for_spare(timeout: float) -> bool:
    """Wait until the spare, if any, is ready (its imports done, its context open); True if one is.
    For measurements: a user's next bake comes seconds after the last, when it is long ready."""
    if _spare is None:
        return False
    _spare.waiting.join(timeout)
    return not _spare.waiting.is_alive() and _spare.process.poll() is None


def spare_process() -> subprocess.Popen | None:
    """The spare solver process waiting for the next bake, or None."""
    return _spare.process if _spare is not None else None


def take_spare() -> Spare | None:
    """The spare, if it runs and was started with the command a bake would use now; else None
    (and a spare that does not fit is ended)."""
    global _spare
    spare, _spare = _spare, None
    if spare is None:
        return None
    if spare.command == child_command(None) and spare.process.poll() is None:
        return spare
    end_process(spare.process)
    return None


def end_spare() -> None:
    """End the spare, if any (the add-on is disabled)."""
    global _spare
    spare, _spare = _spare, None
    if spare is not None:
        end_process(spare.process)


@dataclass
class SolveResult:
    images: dict  # object name -> float32 (H, W, 4) linear RGBA, alpha = coverage
    report: dict  # the solve's report (Report.to_dict())
    summary: str  # Report.summary_line(): what the bake simulated and skipped


def ended_badly(code: int) -> str:
    if code < 0:
        try:
            name = signal.Signals(-code).name
        except ValueError:
            name = f"signal {-code}"
        return f"the solver process crashed ({name}), perhaps in the OpenGL driver; nothing was changed"
    return f"the solver process ended unexpectedly (exit status {code}); nothing was changed, details on the console"


class BakeWorker:
    """One solve in a child process. start(); then poll() (or wait()) until it returns True, and
    read `result` or `error`; take_preview() gives the newest images of a progressive solve so far;
    cancel() ends it at once (it writes only into its own folder, so nothing can be half written);
    discard() ends it and removes its files, whatever state it is in."""

    def __init__(self, scene: Scene, settings: SolveSettings, objects: list[str], lightmaps: LightmapSettings,
                 preview_interval: float | None = None, clock: BakeClock | None = None):
        self.scene, self.settings, self.objects, self.lightmaps = scene, settings, objects, lightmaps
        self.preview_interval = preview_interval  # seconds between previews; None: none (scripts)
        self.clock = clock if clock is not None else BakeClock()  # a bake's runs from its export on
        self.result: SolveResult | None = None
        self.error: BaseException | None = None
        self.cancelled = False
        self.directory: Path | None = None
        self._process: subprocess.Popen | None = None
        self._spare_waiting: threading.Thread | None = None
        self._reader: threading.Thread | None = None
        self._lock = threading.Lock()
        self._messages: list[dict] = []  # read, not yet handled by the main thread
        self._news = threading.Event()  # set by the reader at each message and at the pipe's end: `wait` wakes at once
        self._last_heard = 0.0
        self._preview: str | None = None
        self._over = False

    @property
    def process(self) -> subprocess.Popen | None:
        """The solver process of this bake (None before `start`)."""
        return self._process

    @property
    def preview_waiting(self) -> bool:
        """Whether a snapshot of a progressive solve came and waits to be taken."""
        return self._preview is not None

    def start(self) -> "BakeWorker":
        self.directory = Path(tempfile.mkdtemp(prefix="radiosity-bake-"))
        protocol.write_job(self.directory, self.scene, self.settings, self.lightmaps, self.objects,
                           self.preview_interval)
        self._process = self._handed_to_spare() or launch(child_command(self.directory))
        self._last_heard = time.monotonic()
        self._reader = threading.Thread(target=self._read, name="radiosity-bake-pipe", daemon=True)
        self._reader.start()
        return self

    def _handed_to_spare(self) -> subprocess.Popen | None:
        spare = take_spare()
        if spare is None:
            return None
        try:
            spare.process.stdin.write(json.dumps(str(self.directory)) + "\n")
            spare.process.stdin.flush()
        except OSError:  # it ended in between
            end_process(spare.process)
            return None
        self._spare_waiting = spare.waiting
        return spare.process

    def _read(self) -> None:
        if self._spare_waiting is not None:  # a spare's "ready" is read by its own thread first
            self._spare_waiting.join()
        for line in self._process.stdout:
            message = protocol.decode(line)
            if message is not None:
                with self._lock:
                    self._last_heard = time.monotonic()
                    self._messages.append(message)
                self._news.set()
        self._news.set()

    def cancel(self) -> None:
        if not self.cancelled and not self._over:
            self.cancelled = True
            self._process.kill()

    def poll(self) -> bool:
        """Handle what the child said; kill it if it hangs. True once it is over."""
        if self._over:
            return True
        with self._lock:
            messages, self._messages = self._messages, []
            silent = time.monotonic() - self._last_heard
        for message in messages:
            self._handle(message)
        if self.result is not None:  # what the bake waits for: the child's teardown is not
            self._over = True
            return True
        if self._process.poll() is None:
            if silent > SILENCE_LIMIT and self.error is None:
                self.error = BakeError(f"the solver stopped responding for {silent:.0f} s (a hung OpenGL driver?);"
                                       f" nothing was changed")
                self._process.kill()
            return False
        self._reader.join(5.0)  # its last messages
        with self._lock:
            messages, self._messages = self._messages, []
        for message in messages:
            self._handle(message)
        self._end(self._process.returncode)
        return True

    def _handle(self, message: dict) -> None:
        kind = message["kind"]
        if kind == "progress":
            self.clock.solving(message["fraction"], message["message"], message.get("eta"),
                              own_estimate=message.get("own_estimate", False))
        elif kind == "stage":
            self.clock.laying_out_lightmaps()
        elif kind == "preview":
            if self._preview is not None:  # superseded before it was shown
                (self.directory / self._preview).unlink(missing_ok=True)
            self._preview = message["file"]
        elif kind == "result":
            self.result = SolveResult(protocol.load_images(self.directory / message["file"]), message["report"],
                                      message["summary"])
            self.clock.finished()
        elif kind == "error" and self.error is None:
            self.error = BakeError(message["message"] if message["user"] else
                                   f"the solver failed unexpectedly ({message['message']}); nothing was changed,"
                                   f" details on the console")

    def _end(self, code: int) -> None:
        self._over = True
        if self.cancelled and self.result is None:
            self.error = SolveCancelled("cancelled")
        elif self.result is None and self.error is None:
            self.error = BakeError(ended_badly(code))

    def take_preview(self) -> dict | None:
        """The newest preview images not taken yet (object name -> RGBA), or None."""
        name, self._preview = self._preview, None
        if name is None or self.directory is None:
            return None
        path = self.directory / name
        images = protocol.load_images(path)
        path.unlink(missing_ok=True)
        return images

    def wait(self, timeout: float | None = None) -> bool:
        """poll() until it returns True (then True) or `timeout` passes (False); woken by the child's
        messages, not by a clock (a 20 ms sleep noticed the result 10 ms late on average)."""
        deadline = None if timeout is None else time.monotonic() + timeout
        while True:
            self._news.clear()  # before poll: a message that comes during it sets it again
            if self.poll():
                return True
            left = None if deadline is None else deadline - time.monotonic()
            if left is not None and left <= 0:
                return False
            # at most WAIT_STEP between polls (a hung child is noticed by poll: SILENCE_LIMIT); once the
            # pipe has ended nothing sets the event, and the child's exit is polled for every 20 ms
            step = WAIT_STEP if self._reader.is_alive() else 0.02
            self._news.wait(step if left is None else min(step, left))

    def discard(self, wait: bool = True) -> None:
        """End the child (if it still runs) and remove its files; the result is dropped. `wait`
        False (a bake that succeeded): the child is killed here, and waiting for its exit (the
        kernel's teardown of its memory) and then removing its folder
        (Windows removes no file of a running process) happen on a thread, which Python's exit
        waits for."""
        process, directory = self._process, self.directory
        self._over = True
        if wait:
            reap(process, directory)
        else:
            if process is not None and process.poll() is None:
                process.kill()
            threading.Thread(target=reap, args=(process, directory), name="radiosity-bake-reap").start()
        if process is not None:
            start_spare()  # for the next bake, now that this one no longer needs the CPU

"""Shared by the real-Blender tier's tests (`make test-blender`): the extension zip installed into
Debian's Blender 5.2 (sid) and 4.3 (trixie), each in a root made by tools/blender_rig.sh, run
headless and under Xvfb. Scripts that run inside Blender are in in_blender/ and leave results.json; the tests here
assert on it. Screenshots and measurements are kept in out/real-blender/<version>/.

Needs root (the rig chroots) and the roots set up (`make test-blender` does both set-ups first);
plain `make test` never collects this folder (tests/conftest.py).
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
RIG = ROOT / "tools/blender_rig.sh"
IN_BLENDER = Path(__file__).resolve().parent / "in_blender"
ARTEFACTS = ROOT / "out/real-blender"
RIG_DIRS = {"5.2": os.environ.get("BLENDER_RIG_DIR_5_2", "/var/cache/blender-rig"),
            "4.3": os.environ.get("BLENDER_RIG_DIR_4_3", "/var/cache/blender-rig-trixie")}
ZIP = ROOT / "dist/radiosity_baker-0.1.0-linux_x64.zip"
SCREEN = "1280x800x24"
# A GUI session runs at nice -15, as if Blender had the machine to itself (other jobs, at 0, yield):
# what the tests measure is the add-on's effect on Blender's UI, not what else loads the machine
# (the solver process stays 10 below Blender either way).
GUI_PRIORITY = ["nice", "-n", "-15"]


class Blender:
    """One real Blender with the extension installed in a user folder of its own."""

    def __init__(self, version: str, rig_dir: str, user: Path):
        self.version, self.rig_dir, self.user = version, rig_dir, user
        self.samples = user / "samples"
        self.artefacts = ARTEFACTS / version
        self.artefacts.mkdir(parents=True, exist_ok=True)

    def run(self, *args: str, gui: bool = False, env: dict | None = None, timeout: float = 300):
        environment = dict(os.environ, BLENDER_RIG_DIR=self.rig_dir, BLENDER_USER_RESOURCES=str(self.user),
                           PYTHONUNBUFFERED="1", **(env or {}))
        environment["BLENDER_RIG_PASSENV"] = " ".join(sorted(env or {}))
        command = (GUI_PRIORITY if gui else []) + [str(RIG), "run"] + (["--gui", "--screen", SCREEN] if gui else []) \
            + ["--", *args]
        result = subprocess.run(command, cwd=ROOT, env=environment, capture_output=True, text=True, timeout=timeout)
        log = self.artefacts / "blender.log"
        with log.open("a") as file:
            file.write(f"$ {' '.join(args)}\n{result.stdout}{result.stderr}\n(exit status {result.returncode})\n")
        return result

    def script(self, name: str, *args: str, blend: Path | None = None, gui: bool = False, out: Path,
               env: dict | None = None, timeout: float = 600) -> dict:
        """Run in_blender/NAME with RIG_OUT=out; returns its results.json (empty if it wrote none)."""
        out.mkdir(parents=True, exist_ok=True)
        (out / "results.json").unlink(missing_ok=True)
        head = ["--enable-event-simulate", "--window-geometry", "0", "0", "1280", "800"] if gui else ["-b"]
        file_args = [str(blend)] if blend is not None else []
        result = self.run(*head, *file_args, "--python", str(IN_BLENDER / name), *args, gui=gui,
                          env={"RIG_OUT": str(out), **(env or {})}, timeout=timeout)
        path = out / "results.json"
        found = json.loads(path.read_text()) if path.exists() else {}
        found["_exit_status"] = result.returncode
        found["_output_tail"] = (result.stdout + result.stderr)[-3000:]
        return found


def keep(found: dict, blender: Blender, name: str) -> None:
    """A record of what a run measured, beside its screenshots."""
    (blender.artefacts / name).write_text(json.dumps({k: v for k, v in found.items() if k != "_output_tail"},
                                                     indent=1, default=str))


def copy_shots(source: Path, blender: Blender) -> None:
    for shot in source.glob("*.png"):
        shutil.copy2(shot, blender.artefacts / shot.name)

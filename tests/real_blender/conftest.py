"""Fixtures of the real-Blender tier (`make test-blender`); see rig_support.py for what it is."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from rig_support import ARTEFACTS, RIG, RIG_DIRS, ROOT, ZIP, Blender


def rig_ready(rig_dir: str) -> bool:
    return subprocess.run([str(RIG), "--dir", rig_dir, "status"], capture_output=True).returncode == 0


@pytest.fixture(scope="session")
def extension_zip() -> Path:
    """The zip `make extension` builds (built here if missing, as `make test-blender` would)."""
    if not ZIP.exists():
        build = subprocess.run([sys.executable, str(ROOT / "tools/build_extension.py"), "--output-dir",
                                str(ZIP.parent)], capture_output=True, text=True)
        assert build.returncode == 0, build.stdout + build.stderr
    return ZIP


def installed_blender(version: str, extension_zip: Path, tmp_path_factory) -> Blender:
    if os.geteuid() != 0:
        pytest.fail("the real-Blender tier needs root (tools/blender_rig.sh chroots into Debian roots)")
    rig_dir = RIG_DIRS[version]
    if not rig_ready(rig_dir):
        pytest.fail(f"no Blender {version} root at {rig_dir}: run `make test-blender`, which sets it up")
    shutil.rmtree(ARTEFACTS / version, ignore_errors=True)  # this run's screenshots and records only
    blender = Blender(version, rig_dir, tmp_path_factory.mktemp(f"blender-{version}-user"))
    installed = blender.run("--command", "extension", "install-file", "-r", "user_default", "-e", str(extension_zip))
    assert installed.returncode == 0 and 'Installed "radiosity_baker"' in installed.stdout, installed.stdout[-2000:]
    made = blender.run("-b", "--factory-startup", "--python", str(ROOT / "tools/make_sample_blends.py"), "--",
                       "--output-dir", str(blender.samples))
    assert made.returncode == 0 and (blender.samples / "cornell_box.blend").exists(), made.stdout[-2000:]
    return blender


_installed: dict = {}


@pytest.fixture(scope="session", params=sorted(RIG_DIRS, reverse=True))
def blender(request, extension_zip, tmp_path_factory) -> Blender:
    """Blender 5.2, then 4.3, each with the zip installed and enabled and the samples it made."""
    if request.param not in _installed:
        _installed[request.param] = installed_blender(request.param, extension_zip, tmp_path_factory)
    return _installed[request.param]

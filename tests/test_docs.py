"""The generated parts of the docs are current: the README's tables match docs/bench/*.json, and
docs/architecture.md's tables match the code (presets, defaults, layering) and its links resolve."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


@pytest.mark.parametrize("tool", ["readme_figures.py", "architecture_tables.py"])
def test_generated_docs_are_current(tool):
    checked = subprocess.run([sys.executable, str(ROOT / "tools" / tool), "--check"], capture_output=True,
                             text=True, timeout=120, cwd=ROOT)
    assert checked.returncode == 0, checked.stdout + checked.stderr


def test_the_readme_stays_short():
    assert len((ROOT / "README.md").read_text().splitlines()) <= 350

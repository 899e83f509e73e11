from pathlib import Path

import pytest

from radiosity_addon.core import GPU

REAL_BLENDER = Path(__file__).resolve().parent / "real_blender"


def pytest_ignore_collect(collection_path, config):
    """The real-Blender tier runs only when asked for by path (`make test-blender`): it needs root
    and the Debian roots of tools/blender_rig.sh, and takes minutes."""
    if collection_path == REAL_BLENDER:
        asked = [Path(arg.split("::")[0]).resolve() for arg in config.args]
        return not any(path == REAL_BLENDER or REAL_BLENDER in path.parents for path in asked)
    return None


@pytest.fixture(scope="session")
def gpu():
    """One OpenGL context, with its program cache, for the whole session (the only GL fixture)."""
    with GPU() as session_gpu:
        yield session_gpu

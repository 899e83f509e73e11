import os
from pathlib import Path

import pytest

# every OpenGL context the tests make, here and in the solver processes they start, logs what the
# driver reports (KHR_debug); a test during which it reported an error fails
os.environ.setdefault("RADIOSITY_GL_DEBUG", "1")

from radiosity_addon.core import GPU  # noqa: E402
from radiosity_addon.core.gpu import debug, resources, shaders  # noqa: E402

EXPECTED_RENDERER = "RADIOSITY_EXPECT_RENDERER"  # make test-zink: the run fails at once on another OpenGL

TESTS = Path(__file__).resolve().parent
REAL_BLENDER = TESTS / "real_blender"
# the tiers (pytest -m NAME): gl is marked in its modules; bpy and blender by folder; cycles here
CYCLES_MODULES = {"test_blender_cycles", "test_blender_samples", "test_blender_lamps", "test_blender_opacity",
                  "test_bench_blend_reference"}  # each bakes Cycles' own reference


def pytest_ignore_collect(collection_path, config):
    """The real-Blender tier runs only when asked for by path (`make test-blender`): it needs root
    and the Debian roots of tools/blender_rig.sh, and takes minutes."""
    if collection_path == REAL_BLENDER:
        asked = [Path(arg.split("::")[0]).resolve() for arg in config.args]
        return not any(path == REAL_BLENDER or REAL_BLENDER in path.parents for path in asked)
    return None


def pytest_collection_modifyitems(config, items):
    for item in items:
        folder = Path(item.fspath).relative_to(TESTS).parts[0]
        if folder == "real_blender":
            item.add_marker(pytest.mark.blender)
        elif folder == "blender":
            item.add_marker(pytest.mark.bpy)
        if Path(item.fspath).stem in CYCLES_MODULES:
            item.add_marker(pytest.mark.cycles)


@pytest.fixture(scope="session")
def gpu():
    """One OpenGL context, with its program cache, for the whole session (the only GL fixture)."""
    with GPU() as session_gpu:
        yield session_gpu


@pytest.fixture(autouse=True)
def no_opengl_problems():
    """Fail the test during which a live context's driver logged an OpenGL error or undefined
    behaviour (a context closed inside the test raised them already)."""
    yield
    problems = []
    for ctx in debug.watched_contexts():
        with resources.active(ctx):
            problems += debug.drain(ctx)
    if problems:
        pytest.fail("\n".join(problems), pytrace=False)


def pytest_report_header(config):
    with GPU() as probe:
        return f"OpenGL: {probe.ctx.info['GL_RENDERER']}, {probe.ctx.info['GL_VERSION']}"


def pytest_sessionstart(session):
    expected = os.environ.get(EXPECTED_RENDERER)
    if expected:
        with GPU() as probe:
            renderer = probe.ctx.info["GL_RENDERER"]
        if expected not in renderer:
            pytest.exit(f"the OpenGL renderer is {renderer}, not {expected}"
                        " (zink needs: apt-get install mesa-vulkan-drivers)", returncode=2)


def pytest_sessionfinish(session, exitstatus):
    """A run of the `gl` tests alone must compile every shader in shaders/ (what makes it a check
    of a second OpenGL implementation)."""
    if session.config.getoption("markexpr") != "gl" or exitstatus != 0 or session.config.getoption("keyword"):
        return
    missing = sorted(set(shaders.stage_files()) - shaders.loaded)
    if missing:
        session.config.pluginmanager.get_plugin("terminalreporter").write_line(
            f"the gl tests compiled no program from {', '.join(missing)}: mark a test that does with gl", red=True)
        session.exitstatus = 1

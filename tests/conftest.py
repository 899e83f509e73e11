import pytest

from radiosity_addon.core import gl


@pytest.fixture(scope="session")
def ctx():
    """One OpenGL context for the whole session (creating one costs ~0.1 s on llvmpipe)."""
    context = gl.create_context()
    yield context
    context.release()

import pytest

from radiosity_addon.core import GPU


@pytest.fixture(scope="session")
def gpu():
    """One OpenGL context, with its program cache, for the whole session (the only GL fixture)."""
    with GPU() as session_gpu:
        yield session_gpu

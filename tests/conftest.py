import numpy as np
import pytest


@pytest.fixture
def rng():
    return np.random.default_rng(12345)


@pytest.fixture(scope="session")
def runtime():
    from clpde.runtime import get_runtime

    return get_runtime("cpu")

"""Numeric warnings are bugs: the suite turns RuntimeWarnings into errors (pyproject.toml),
and these inputs, which printed them, now give none."""

import warnings

import numpy as np
import pytest

import clpde
from clpde.regions.mesh import surface_mesh
from clpde.surface import ImplicitSurface


@pytest.fixture
def far_sphere():
    """A sphere's distance with one face of the volume at 1e300, beyond float32's range."""
    z, y, x = np.mgrid[:20, :20, :20] - 9.5
    phi = np.sqrt(x * x + y * y + z * z) - 3
    phi[0] = 1e300
    return phi


def test_huge_distances_upload_without_overflow(far_sphere):
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)
        surf = ImplicitSurface(far_sphere, 1.0)
        assert np.isfinite(surf.grid.download(surf.psi_dev)).all()
        assert len(surface_mesh(far_sphere).vertices) > 0


def test_tracking_a_single_row_gives_no_empty_median():
    frames = np.zeros((2, 1, 2), np.uint8)
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)
        masks = clpde.track(frames, np.array([[False, True]]), max_iterations=3)
    assert masks.shape == frames.shape


def test_the_suite_treats_runtime_warnings_as_errors():
    with pytest.raises(RuntimeWarning):
        np.float32(np.float64(1e300))  # overflow in cast: an error under pyproject's filter

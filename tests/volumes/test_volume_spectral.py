"""3D spectral inpainting (clpde/volumes/spectral.py): the thresholding kernels against the
numpy reference in both precisions, the block positions against a direct count, and an
analytic volume whose fill is closer than the harmonic's and the biharmonic's."""

import numpy as np
import pytest

from clpde.runtime import get_runtime
from clpde.volumes import inpaint_volume
from clpde.volumes.grid import VolumeGrid
from clpde.volumes.spectral import block_corners, spectral_fill, thresholds
from tests.reference import volumes as ref


def _hole(shape):
    hole = np.zeros(shape, bool)
    hole[2:5, 3:6, 0:5] = True  # touches the box's border at x = 0
    hole[6, 7, 8] = True  # a voxel in the box's far corner: one block holds it
    return hole


def test_block_corners_are_the_blocks_that_hold_hole_voxels():
    hole = _hole((7, 8, 9))
    want = [
        (z, y, x) for z, y, x in np.ndindex(4, 5, 6) if hole[z : z + 4, y : y + 4, x : x + 4].any()
    ]
    assert block_corners(hole).tolist() == [list(c) for c in want]


@pytest.mark.parametrize("dtype, atol", [(np.float64, 1e-12), (np.float32, 1e-5)])
def test_the_kernels_equal_the_reference(rng, dtype, atol):
    u = rng.random((2, 7, 8, 9))
    hole = _hole((7, 8, 9))
    grid = VolumeGrid(get_runtime("cpu"), u.shape, np.dtype(dtype), np.ones(3))
    out = spectral_fill(grid, u, hole, thresholds())
    for c in range(2):
        want = ref.spectral_fill(u[c], hole, thresholds())
        np.testing.assert_allclose(out[c], want, atol=atol)
        assert np.abs(want - u[c]).max() > 0.2  # the passes moved the hole
    assert (out[:, ~hole] == u[:, ~hole]).all()


def test_a_smooth_volume_is_filled_closer_than_by_the_smooth_fills():
    z, y, x = np.indices((16, 20, 24), dtype=float)
    f = 0.5 + 0.3 * np.sin(x / 3) * np.cos(y / 4) + 0.1 * z / 16
    mask = np.zeros(f.shape, bool)
    mask[5:10, 6:14, 7:17] = True
    err = {
        m: np.abs(inpaint_volume(f, mask, method=m, dtype=np.float64) - f)[mask].max()
        for m in ("harmonic", "biharmonic", "spectral")
    }
    assert (inpaint_volume(f, mask, method="spectral") == f)[~mask].all()
    # measured 0.014 against 0.018 (biharmonic) and 0.099 (harmonic)
    assert err["spectral"] < 0.8 * err["biharmonic"]
    assert err["spectral"] < err["harmonic"] / 5

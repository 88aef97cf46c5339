"""3D biharmonic inpainting (clpde/volumes/biharmonic.py): the
conjugate-gradient kernel's fill against the numpy reference's direct solve, a biharmonic quartic of
physical coordinates filled exactly with thick slices (and not by the harmonic fill), and
the method's name checked."""

import numpy as np
import pytest

import clpde
from clpde.runtime import get_runtime
from clpde.volumes import inpaint_volume
from clpde.volumes.biharmonic import biharmonic_cg
from clpde.volumes.grid import VolumeGrid
from tests.reference import volumes as ref

H = (2.0, 1.0, 0.5)


def _grid(shape):
    return VolumeGrid(get_runtime("cpu"), shape, np.dtype(np.float64), np.array(H))


def test_conjugate_gradients_reach_the_reference_fill(rng):
    u = rng.random((2, 7, 8, 9))
    hole = np.zeros((7, 8, 9), bool)
    hole[1:6, 2:6, 0:6] = True  # touches the box's border: Neumann there
    out = biharmonic_cg(_grid(u.shape), u, hole, max_iterations=1000, rtol=1e-12)
    want = ref.biharmonic_fill(u, hole, H)
    np.testing.assert_allclose(out, want, atol=1e-6 * np.abs(want).max())
    assert (out[:, ~hole] == u[:, ~hole]).all()
    assert np.abs(want - u).max() > 0.1  # the start was not already the answer


def _polynomial(shape, spacing):
    """x^4 - 3 x^2 z^2 + x^2 z + x y z + y^2 in physical coordinates: Lap = 6x^2 - 6z^2 + 2z
    + 2, so Lap^2 = 0. The central second difference of x^4 is 12 x^2 + 2 hx^2 (exact on
    the rest), a constant off, so L L vanishes at every voxel whose stencil fits the volume:
    the discrete fill is the function itself. In voxel indices (unit spacing) its L L is
    24 hx^2 (hx^2 - hz^2), not zero: the spacing matters."""
    z, y, x = np.indices(shape, dtype=float)
    z, y, x = z * spacing[0], y * spacing[1], x * spacing[2]
    return x**4 - 3 * x * x * z * z + x * x * z + x * y * z + y * y


def test_a_biharmonic_polynomial_is_filled_exactly_with_thick_slices():
    f = _polynomial((12, 18, 24), H)
    mask = np.zeros(f.shape, bool)
    mask[3:9, 4:14, 4:20] = True
    mask[9, 15:16, 20:22] = True  # a second component, in its own box
    out = inpaint_volume(f, mask, method="biharmonic", spacing=H, tol=1e-8, dtype=np.float64)
    assert (out[~mask] == f[~mask]).all()
    assert np.abs(out - f).max() < 1e-5 * np.ptp(f)
    # the harmonic fill of the same holes is another function (Lap f != 0)
    harmonic = inpaint_volume(f, mask, method="harmonic", spacing=H, tol=1e-8, dtype=np.float64)
    assert np.abs(harmonic - f).max() > 5e-4 * np.ptp(f)  # 50x the tolerance above
    # and so is the biharmonic fill without the spacing
    wrong = inpaint_volume(f, mask, method="biharmonic", tol=1e-8, dtype=np.float64)
    assert np.abs(wrong - f).max() > 5e-4 * np.ptp(f)


def test_channels_and_dtype_kept(rng):
    vol = (rng.random((9, 10, 11, 2)) * 60000).astype(np.uint16)
    mask = np.zeros(vol.shape[:3], bool)
    mask[3:6, 4:7, 2:8] = True
    before = vol.copy()
    out = inpaint_volume(vol, mask, channel_axis=-1)  # the default: biharmonic
    assert out.dtype == np.uint16 and out.shape == vol.shape
    assert (vol == before).all() and (out[~mask] == vol[~mask]).all()


def test_an_unknown_method_gives_one_line():
    with pytest.raises(clpde.InputError, match="method must be one of"):
        inpaint_volume(np.zeros((4, 5, 6)), np.zeros((4, 5, 6), bool), method="transport")

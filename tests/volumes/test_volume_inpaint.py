"""3D harmonic inpainting (clpde/volumes/inpaint.py): the SOR kernel against the numpy
reference, a harmonic function of physical coordinates filled exactly with thick slices
(and not without the spacing), boxes per component, and bad input."""

import numpy as np
import pytest

import clpde
from clpde.errors import InputError
from clpde.runtime import get_runtime
from clpde.volumes import inpaint_volume
from clpde.volumes.grid import VolumeGrid
from clpde.volumes.inpaint import sor
from tests.reference import volumes as ref

H = (2.0, 1.0, 0.5)


def test_sor_sweeps_match_the_reference(rng):
    u = rng.random((2, 6, 7, 8))
    hole = np.zeros((6, 7, 8), bool)
    hole[1:5, 2:6, 0:5] = True  # touches the box's border: Neumann there
    grid = VolumeGrid(get_runtime("cpu"), u.shape, np.dtype(np.float64), np.array(H))
    out = sor(grid, u, hole, tol=1e-30, max_sweeps=10)
    omega = 2.0 / (1.0 + np.sin(np.pi / 8))
    np.testing.assert_allclose(out, ref.harmonic_sweeps(u, hole, omega, H, 10), atol=1e-12)


def _quadratic(spacing):
    """x^2 - z^2 in physical coordinates: harmonic, and the seven-point Laplacian with the
    spacing is exact on quadratics, so the discrete fill is the function itself."""
    z, y, x = np.indices((20, 24, 28), dtype=float)
    return (x * spacing[2]) ** 2 - (z * spacing[0]) ** 2


def test_a_harmonic_function_is_filled_exactly_with_thick_slices():
    f = _quadratic(H)
    mask = np.zeros(f.shape, bool)
    mask[5:15, 6:18, 4:20] = True
    mask[2:4, 1:4, 1:5] = True  # a second component, in its own box
    out = inpaint_volume(f, mask, method="harmonic", spacing=H, tol=1e-8, dtype=np.float64)
    assert np.abs(out - f).max() < 1e-6 * np.ptp(f)
    assert (out[~mask] == f[~mask]).all()
    # the spacing matters: the unit-spacing fill of the same voxels is another function
    wrong = inpaint_volume(f, mask, method="harmonic", tol=1e-8, dtype=np.float64)
    assert np.abs(wrong - f).max() > 0.01 * np.ptp(f)


def test_channels_dtype_and_input_kept(rng):
    vol = (rng.random((10, 11, 12, 2)) * 60000).astype(np.uint16)
    mask = np.zeros(vol.shape[:3], bool)
    mask[3:7, 4:8, 2:9] = True
    before = vol.copy()
    out = inpaint_volume(vol, mask, channel_axis=-1, method="harmonic")
    assert out.dtype == np.uint16 and out.shape == vol.shape
    assert (vol == before).all() and (out[~mask] == vol[~mask]).all()
    lo, hi = vol[~mask].min(axis=0), vol[~mask].max(axis=0)
    assert (out[mask] >= lo).all() and (out[mask] <= hi).all()  # the maximum principle


@pytest.mark.parametrize(
    "mask,match",
    [
        (np.zeros((4, 5, 5), bool), "mask has shape"),
        (np.ones((4, 5, 6), bool), "whole volume"),
    ],
)
def test_bad_masks_give_one_line(mask, match):
    with pytest.raises(clpde.InputError, match=match):
        inpaint_volume(np.zeros((4, 5, 6)), mask)


def test_progress_hears_the_voxels_filled_box_by_box():
    vol = np.indices((8, 9, 10)).sum(0) / 25.0
    mask = np.zeros(vol.shape, bool)
    mask[1:3, 1:3, 1:3] = True  # 8 voxels
    mask[5:7, 5:8, 6:9] = True  # 18 voxels, another box
    heard = []
    out = inpaint_volume(vol, mask, progress=lambda done, total: heard.append((done, total)))
    assert heard in ([(8, 26), (26, 26)], [(18, 26), (26, 26)])  # one call per box
    np.testing.assert_array_equal(out, inpaint_volume(vol, mask, progress=False))

    class Cancel(Exception):
        pass

    def cancel(done, total):
        raise Cancel

    with pytest.raises(Cancel):
        inpaint_volume(vol, mask, progress=cancel)
    with pytest.raises(clpde.InputError, match="progress must be"):
        inpaint_volume(vol, mask, progress="yes")


def test_clpde_inpaint_with_spacing_fills_a_volume(rng):
    """clpde.inpaint(volume, mask, spacing=...) is inpaint_volume's fill, method included;
    the planar options are refused in one line instead of being ignored."""
    volume = rng.random((8, 10, 12)).astype(np.float32)
    mask = np.zeros(volume.shape, bool)
    mask[3:5, 4:6, 4:8] = True
    for method in (None, "harmonic"):
        out = clpde.inpaint(volume, mask, spacing=(2, 1, 1), method=method)
        expect = inpaint_volume(volume, mask, spacing=(2, 1, 1), method=method or "biharmonic")
        assert out.dtype == volume.dtype and np.array_equal(out, expect)
    with pytest.raises(InputError, match="leave out grow"):
        clpde.inpaint(volume, mask, spacing=(1, 1, 1), grow=2)

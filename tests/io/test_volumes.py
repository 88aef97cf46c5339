"""Volume files (NIfTI, multi-page TIFF): round trips keep dtype, values, axes and spacing;
nibabel's own test volumes read as nibabel reads them; writes are atomic."""

import gzip
import os
import sys

import numpy as np
import pytest

from clpde.errors import InputError
from clpde.io import VolumeInfo, read_volume, write_volume

nib = pytest.importorskip("nibabel")
NIB_DATA = os.path.join(os.path.dirname(nib.__file__), "tests", "data")


def _volume(rng, dtype, shape):
    if np.dtype(dtype).kind == "f":
        return rng.standard_normal(shape).astype(dtype)
    if np.dtype(dtype).kind == "b":
        return rng.random(shape) > 0.5
    info = np.iinfo(dtype)
    return rng.integers(info.min, info.max, size=shape, endpoint=True).astype(dtype)


@pytest.mark.parametrize("suffix", [".nii", ".nii.gz", ".tif"])
@pytest.mark.parametrize(
    "dtype", [np.uint8, np.int8, np.int16, np.uint16, np.int32, np.int64, np.float32, np.float64]
)
def test_round_trip_keeps_dtype_values_and_spacing(tmp_path, rng, suffix, dtype):
    vol = _volume(rng, dtype, (3, 5, 7))  # distinct sizes: a swapped axis would show
    path = write_volume(tmp_path / f"v{suffix}", vol, spacing=(2.5, 1.0, 0.5))
    back, info = read_volume(path, with_info=True)
    assert back.dtype == vol.dtype and back.shape == vol.shape
    np.testing.assert_array_equal(back, vol)
    assert info.spacing == (2.5, 1.0, 0.5)


@pytest.mark.parametrize("suffix", [".nii.gz", ".tif"])
def test_channels_last_round_trip(tmp_path, rng, suffix):
    vol = _volume(rng, np.uint8, (2, 4, 6, 3))
    back = read_volume(write_volume(tmp_path / f"rgb{suffix}", vol))
    np.testing.assert_array_equal(back, vol)


def test_nifti_axes_are_reversed_to_slices_first(tmp_path, rng):
    vol = _volume(rng, np.float32, (3, 5, 7))
    path = write_volume(tmp_path / "v.nii.gz", vol, spacing=(4.0, 2.0, 1.0))
    with open(path, "rb") as f:
        assert f.read(2) == b"\x1f\x8b"  # gzip, as the name says
    img = nib.load(str(path))
    assert img.shape == (7, 5, 3)  # NIfTI's (x, y, z)
    np.testing.assert_array_equal(np.asarray(img.dataobj), vol.transpose(2, 1, 0))
    assert img.header.get_zooms() == (1.0, 2.0, 4.0)


@pytest.mark.parametrize("name", ["anatomical.nii", "example4d.nii.gz", "standard.nii.gz"])
def test_nibabel_test_volumes_read_as_nibabel_reads_them(tmp_path, name):
    path = os.path.join(NIB_DATA, name)
    img = nib.load(path)
    vol, info = read_volume(path, with_info=True)
    raw = np.asarray(img.dataobj)
    want = raw.transpose((2, 1, 0, 3) if raw.ndim == 4 else (2, 1, 0))
    np.testing.assert_array_equal(vol, want)
    assert vol.dtype == raw.dtype
    assert info.spacing == tuple(float(z) for z in reversed(img.header.get_zooms()[:3]))
    # written back with its info, the file keeps its place in world space
    out = write_volume(tmp_path / ("out" + name[name.index(".") :]), vol, like=info)
    again = nib.load(str(out))
    np.testing.assert_allclose(again.affine, img.affine)
    np.testing.assert_array_equal(np.asarray(again.dataobj), raw)


def test_imagej_tiff_spacing_is_read(tmp_path, rng):
    import tifffile

    vol = _volume(rng, np.uint16, (4, 6, 8))
    path = tmp_path / "ij.tif"
    tifffile.imwrite(
        path,
        vol,
        imagej=True,
        resolution=(1 / 0.25, 1 / 0.5),
        metadata={"spacing": 3.0, "axes": "ZYX"},
    )
    back, info = read_volume(path, with_info=True)
    np.testing.assert_array_equal(back, vol)
    assert info.spacing == pytest.approx((3.0, 0.5, 0.25))


def test_failed_write_keeps_the_old_file_and_leaves_nothing(tmp_path, rng):
    path = tmp_path / "v.nii.gz"
    vol = _volume(rng, np.int16, (2, 3, 4))
    write_volume(path, vol)
    before = path.read_bytes()
    with pytest.raises(InputError, match="NIfTI cannot hold"):
        write_volume(path, np.zeros((2, 3, 4), np.float16))
    assert path.read_bytes() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["v.nii.gz"]
    with gzip.open(path) as f:
        assert len(f.read()) > 0


def test_bad_inputs_say_what_to_do(tmp_path):
    with pytest.raises(InputError, match="unsupported volume format"):
        read_volume(tmp_path / "v.png")
    with pytest.raises(InputError, match="does not exist"):
        read_volume(tmp_path / "v.nii")
    with pytest.raises(InputError, match=r"\(Z, Y, X\)"):
        write_volume(tmp_path / "v.tif", np.zeros((4, 4)))
    with pytest.raises(InputError, match="spacing"):
        write_volume(tmp_path / "v.tif", np.zeros((2, 4, 4)), spacing=(1, 0, 1))
    (tmp_path / "bad.nii").write_bytes(b"not a nifti file at all" * 20)
    with pytest.raises(InputError, match="cannot read"):
        read_volume(tmp_path / "bad.nii")


def test_missing_nibabel_is_one_line_naming_the_install(tmp_path, monkeypatch):
    monkeypatch.setitem(sys.modules, "nibabel", None)  # import nibabel now fails
    with pytest.raises(InputError, match="pip install nibabel") as exc:
        write_volume(tmp_path / "v.nii", np.zeros((2, 2, 2)))
    assert "\n" not in str(exc.value)
    assert not (tmp_path / "v.nii").exists()


def test_volume_info_defaults():
    assert VolumeInfo().spacing == (1.0, 1.0, 1.0)

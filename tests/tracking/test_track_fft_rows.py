"""fft_rows: match_shift's transforms with the zero rows left out are scipy.fft's rfft2 /
irfft2. Bit for bit on the scipy measured (benchmarks/track_default_bitwise.py checks the
tracker's outputs); here to rounding, so that a scipy whose pocketfft orders its sums
otherwise does not fail a correct transform."""

import numpy as np
import pytest
from scipy import fft as sfft

from clpde.tracking.fft_rows import irfft2_rows, rfft2_rows


def _cases(seed, count=60):
    rng = np.random.default_rng(seed)
    for trial in range(count):
        r = int(rng.integers(1, 33))
        h, w = int(rng.integers(1, 100)), int(rng.integers(1, 100))
        if trial % 5 == 0:  # one or a few columns: spectra with exact zeros
            w = int(rng.integers(1, 4))
        shape = tuple(sfft.next_fast_len(n + 3 * r, real=True) for n in (h, w))
        k = int(rng.integers(1, 7))
        a = np.zeros((k,) + shape)
        top = int(rng.integers(0, shape[0] - h + 1))
        values = rng.standard_normal((k, h, w))
        if trial % 3 == 0:  # a 0/1 weight, as match_shift's
            values = (values > 0).astype(np.float64)
        a[:, top : top + h, :w] = values
        yield a, slice(top, top + h), r


@pytest.mark.parametrize("seed", [0, 1])
def test_rfft2_rows_is_rfft2_bit_for_bit(seed):
    for a, rows, _ in _cases(seed):
        expected = sfft.rfft2(a, axes=(-2, -1))
        got = rfft2_rows(a, rows)
        assert got.dtype == expected.dtype and got.shape == expected.shape
        np.testing.assert_allclose(got, expected, rtol=0, atol=1e-12 * max(1.0, abs(a).sum()))


@pytest.mark.parametrize("seed", [2, 3])
def test_irfft2_rows_is_irfft2_rows_bit_for_bit(seed):
    for a, _, r in _cases(seed):
        shape = a.shape[-2:]
        spectrum = sfft.rfft2(a, axes=(-2, -1))
        spectrum = spectrum * np.conj(spectrum[::-1]) + 0.25  # a product, as match_shift's
        near = np.r_[0 : r + 1, shape[0] - r : shape[0]]
        expected = sfft.irfft2(spectrum, shape, axes=(-2, -1))[:, near]
        got = irfft2_rows(spectrum, near, shape)
        assert got.shape == expected.shape
        np.testing.assert_allclose(
            got, expected, rtol=0, atol=1e-12 * max(1.0, abs(expected).max())
        )


def test_wrong_rows_would_be_caught():
    # the checks above can fail: the inverse's rows taken one off are not the rows asked for
    a, _, r = next(_cases(4))
    shape = a.shape[-2:]
    spectrum = sfft.rfft2(a, axes=(-2, -1))
    near = np.r_[0 : r + 1, shape[0] - r : shape[0]]
    expected = sfft.irfft2(spectrum, shape, axes=(-2, -1))[:, near]
    wrong = irfft2_rows(spectrum, (near + 1) % shape[0], shape)
    assert not np.allclose(wrong, expected, rtol=0, atol=1e-12 * max(1.0, abs(expected).max()))

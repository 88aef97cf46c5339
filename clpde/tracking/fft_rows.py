"""The 2-D real FFTs of appearance.match_shift with the rows that need no work left out, bit
for bit scipy.fft's rfft2 / irfft2 (issue 35: colour=True's masked correlation transforms
three channels, their squares and their templates a frame).

pocketfft's 2-D real transforms are two passes: the last axis' real transform of every row,
then the first axis' complex transform of every column (forward); the first axis' inverse,
then the last axis' real inverse of every row, the 1 / (H W) factor applied in that last
pass (inverse). A row that is zero before the forward's first pass transforms to the same
values whatever else is in the array, so only the rows that hold data are transformed; the
inverse's last pass is run on the rows the caller reads only. Each 1-D transform is the same
plan on the same values, so the results are the same bits (tests/tracking/
test_track_fft_rows.py checks it on random sizes).
"""

from __future__ import annotations

import numpy as np
from scipy import fft as sfft


def rfft2_rows(a: np.ndarray, rows: slice) -> np.ndarray:
    """sfft.rfft2(a, axes=(-2, -1)) of real `a` (..., H, W) that is zero outside `rows`."""
    h, w = a.shape[-2:]
    half = np.empty(a.shape[:-2] + (h, w // 2 + 1), complex)
    half[...] = sfft.rfft(np.zeros(w))  # a zero row's transform (its zeros' signs too)
    half[..., rows, :] = sfft.rfft(a[..., rows, :], axis=-1)
    return sfft.fft(half, axis=-2, overwrite_x=True)


def irfft2_rows(spectrum: np.ndarray, rows: np.ndarray, shape: tuple[int, int]) -> np.ndarray:
    """The rows `rows` (indices) of sfft.irfft2(spectrum, shape, axes=(-2, -1))."""
    columns = sfft.ifft(spectrum, axis=-2, norm="forward")  # unscaled, as in irfft2
    out = sfft.irfft(columns[..., rows, :], shape[1], axis=-1, norm="forward")
    # (the factor as pocketfft finds it, 1 / N in long double rounded to double, and applied
    # as it does, one product per value)
    out *= np.float64(1 / np.longdouble(shape[0] * shape[1]))
    return out

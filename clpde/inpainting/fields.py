"""Thick clusters of damage in a Gaussian random field: the harmonic or the biharmonic fill.

A surface whose differences between neighbours are Gaussian at two scales (a fractal or
ridged height field, a smooth scalar field with fine stochastic detail) has no edges or
lines for the spectral fill to continue: its sparse Fourier model fits the field's fine
detail as if it were structure, and on the corpus's voids in such fields it trailed the
biharmonic fill (issue 37). For a Gaussian field the best linear predictor of a hole is the
conditional mean under the field's own variogram. That variogram is measured here as a
power law, gamma(h) ~ h^alpha (alpha = 2H, the Hurst exponent H fitted on the cluster's
window: the known pixels' differences at lags 1-8 px, along rows and columns). A membrane
(the harmonic fill, Laplacian zero) is the conditional mean of a field at H -> 0, whose
covariance is the Laplacian's Green's function (log-correlated); the thin plate (the
biharmonic fill) that at H -> 1, a smooth field. A cluster takes the harmonic fill where
alpha is below SMOOTH_ALPHA (H below 1/2), else the biharmonic fill; both solved on the host
per cluster (smooth.py). A variogram that stops growing at the largest lags (below
MIN_GROWTH: a texture correlated over a few pixels, not a power law) leaves the cluster to
the spectral fill. (Ordinary kriging with the fitted power law did no better than the
harmonic fill on the calibration half's fractal voids, 20.36 / 22.31 dB against 20.31 /
22.64, and its dense solves took 3.3x the default's time on those voids:
docs/inpainting.md, "Voids in Gaussian fields".)

"Gaussian": the kurtosis (4th moment over the squared 2nd) of the grey known pixels'
differences between 4-neighbours, and of those between the means of neighbouring 2 x 2
bins wholly known, is within KURTOSIS_BAND of 3 (a Gaussian's) at both scales, each over at
least MIN_PAIRS differences. Photos, microscopy and 16-bit binned data (edges, lines: a few
large differences) score above 4, gratings about 1.5; white noise added to a photo makes its
pixels' differences Gaussian, but not its bins' (docs/inpainting.md, "Thin damage in
Gaussian surrounds"). Chosen on the calibration half.
"""

from __future__ import annotations

import numpy as np
from scipy import ndimage

from .smooth import grown_box

KURTOSIS_BAND = 0.5  # |kurtosis - 3| below this at both scales: a Gaussian field
MIN_PAIRS = 256  # differences needed at each scale for the kurtosis to count
LAGS = (1, 2, 4, 8)  # px: the variogram's power law is fitted over these lags
SMOOTH_ALPHA = 1.0  # a variogram exponent at least this (H >= 1/2): the biharmonic fill
MIN_GROWTH = 0.2  # the variogram's least slope between the last two lags (a power law)


def _differences(grey, ok, lag=1):
    """The differences between known pixels `lag` apart, along rows and along columns."""
    a = (grey[:, lag:] - grey[:, :-lag])[ok[:, lag:] & ok[:, :-lag]]
    b = (grey[lag:, :] - grey[:-lag, :])[ok[lag:, :] & ok[:-lag, :]]
    return np.concatenate([a, b])


def _kurtosis(d) -> float:
    if d.size < MIN_PAIRS:
        return np.inf
    d = d - d.mean()
    d2 = d * d  # (d**4 would call pow: several times slower)
    m2 = float(d2.mean())
    return float((d2 * d2).mean()) / m2**2 if m2 > 0 else np.inf


def gaussian(grey, ok) -> bool:
    """Whether the known pixels (`ok`) of `grey` (a window) differ from their neighbours as
    a Gaussian field does, at the pixels' scale and at 2 x 2 bins' (module docstring)."""
    grey = np.where(ok, grey, 0.0)
    if not abs(_kurtosis(_differences(grey, ok)) - 3) < KURTOSIS_BAND:
        return False
    h, w = (grey.shape[0] // 2) * 2, (grey.shape[1] // 2) * 2
    bins = grey[:h, :w].reshape(h // 2, 2, w // 2, 2).mean(axis=(1, 3))
    whole = ok[:h, :w].reshape(h // 2, 2, w // 2, 2).all(axis=(1, 3))
    return abs(_kurtosis(_differences(bins, whole)) - 3) < KURTOSIS_BAND


def variogram(grey, ok):
    """The mean squared difference of the known pixels at each lag of LAGS (along rows and
    columns; an array), or None where a lag has too few pairs or no variation."""
    grey = np.where(ok, grey, 0.0)
    g = []
    for lag in LAGS:
        d = _differences(grey, ok, lag)
        if d.size < MIN_PAIRS // 4:
            return None
        g.append(float((d * d).mean()))
    return np.asarray(g) if min(g) > 0 else None


def power_law(grey, ok) -> float:
    """The variogram's power-law exponent on the known pixels: the slope of the log
    variogram against the log lag over LAGS; NaN where it cannot be fitted, or where the
    variogram stops growing (its slope between the last two lags below MIN_GROWTH: a
    texture correlated over a few pixels only, no power law, which the spectral fill keeps)."""
    g = variogram(grey, ok)
    if g is None or np.log(g[-1] / g[-2]) / np.log(LAGS[-1] / LAGS[-2]) < MIN_GROWTH:
        return float("nan")
    return float(np.polyfit(np.log(LAGS), np.log(g), 1)[0])


def gaussian_clusters(data, omega, clusters, labels, window):
    """Among `labels` (of the image `clusters`), the clusters whose window (their box grown
    by `window` px) is a Gaussian field (`gaussian`), split by their variogram's exponent:
    (the labels for the harmonic fill, the labels for the biharmonic fill; where no power
    law fits, neither: the spectral fill keeps the cluster)."""
    known = ~np.asarray(omega, bool)
    grey = np.asarray(data, np.float64).mean(axis=0)
    slices = ndimage.find_objects(clusters)
    rough, smooth = [], []
    for lab in labels:
        w = grown_box(slices[lab - 1], window, known.shape)
        if gaussian(grey[w], known[w]):
            alpha = power_law(grey[w], known[w])
            if alpha < SMOOTH_ALPHA:
                rough.append(int(lab))
            elif alpha >= SMOOTH_ALPHA:
                smooth.append(int(lab))
    return np.asarray(rough, int), np.asarray(smooth, int)

"""method="pick": the spectral fill, except where a cluster of damage sits in a periodic
pattern, which the exemplar copies instead.

The spectral fill (spectral.py) leads on thin damage and photos but cannot continue a
periodic pattern across a hole of several periods (issue 37: 7.85 dB behind FSR-best on the
corpus's periodic class), where the exemplar copies it exactly. What decides is measured at
the hole, cheaply: for each cluster of damage (a connected component of the hole grown by
1 px) at least MIN_RADIUS px thick, the periodicity of the known pixels in a window of its
bounding box grown by WINDOW px (choose.periodicity: the largest autocorrelation of the
detail over lags of 6-32 px; FFTs on the host). A cluster whose surround repeats at least
as well as choose.MIN_PERIODICITY (the exemplar's own threshold for copying without a
structure guide) takes the exemplar's fill; every other takes the spectral fill. A box
without such a cluster is filled by the spectral fill alone, exactly as method="spectral".

Chosen on the calibration half of tests/cases/inpaint_corpus.py's corpus
(benchmarks/inpaint_default_route.py; docs/inpainting.md has both halves). A smooth route
(the biharmonic fill where the surround has little texture) was measured there and gained
nothing at any threshold, so it is not here.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy import ndimage

from ..errors import InputError
from . import choose
from .exemplar import ExemplarOptions
from .registry import keywords, load, register
from .spectral import MARGIN as SPECTRAL_MARGIN
from .spectral import SpectralOptions

DESCRIPTION = "the spectral fill, and the exemplar's where a cluster sits in a periodic pattern"

MIN_RADIUS = 3.0  # thinner clusters: the spectral fill (a scratch needs no period copied)
WINDOW = 24  # px of surround measured around each cluster's bounding box


@dataclass(frozen=True)
class PickOptions:
    """method="pick"'s options.

    Parameters
    ----------
    spectral : SpectralOptions
        The spectral fill's options.
    exemplar : ExemplarOptions
        The exemplar's options (on the periodic clusters).
    periodicity : float
        A cluster whose surround's periodicity is at least this goes to the exemplar.
    """

    spectral: SpectralOptions = field(default_factory=SpectralOptions)
    exemplar: ExemplarOptions = field(default_factory=ExemplarOptions)
    periodicity: float = choose.MIN_PERIODICITY

    def __post_init__(self) -> None:
        if not isinstance(self.spectral, SpectralOptions):
            raise InputError(f"spectral must be SpectralOptions, not {self.spectral!r}")
        if not isinstance(self.exemplar, ExemplarOptions):
            raise InputError(f"exemplar must be ExemplarOptions, not {self.exemplar!r}")
        if not 0 <= self.periodicity <= 1:  # NaN too
            raise InputError(f"periodicity must be in [0, 1], not {self.periodicity!r}")


def periodic_clusters(data, omega, periodicity=choose.MIN_PERIODICITY):
    """The hole's pixels whose cluster sits in a periodic surround (module docstring): a
    bool mask, within omega."""
    omega = np.asarray(omega, bool)
    known = ~omega
    dist = ndimage.distance_transform_edt(known)
    clusters, count = ndimage.label(dist <= 1, np.ones((3, 3), bool))
    depth = ndimage.distance_transform_edt(omega)
    radius = np.asarray(ndimage.maximum(depth, clusters, np.arange(1, count + 1))).reshape(-1)
    thick = np.flatnonzero(radius >= MIN_RADIUS)
    if not thick.size:
        return np.zeros_like(omega)
    detail, ok = choose._detail(data, known)
    slices = ndimage.find_objects(clusters)
    chosen = []
    for k in thick:
        s = slices[k]
        y0, y1 = max(s[0].start - WINDOW, 0), s[0].stop + WINDOW
        x0, x1 = max(s[1].start - WINDOW, 0), s[1].stop + WINDOW
        if choose._periodicity(detail[y0:y1, x0:x1], ok[y0:y1, x0:x1]) >= periodicity:
            chosen.append(k + 1)
    return np.isin(clusters, chosen) & omega


def _margin(omega, o: PickOptions) -> int:
    # the spectral fill's boxes, so that a box without a periodic cluster is filled
    # exactly as method="spectral" fills it; the exemplar searches the box
    return SPECTRAL_MARGIN(omega, o.spectral.block, o.spectral.border)


@register("pick", PickOptions, margin=_margin)
def solve(
    data,
    omega,
    runtime,
    *,
    dtype=np.float32,
    progress=None,
    seed=None,
    spectral=None,
    exemplar=None,
    periodicity=choose.MIN_PERIODICITY,
):
    """The picked fill of one box (module docstring; registry.py's protocol)."""
    spectral = SpectralOptions() if spectral is None else spectral
    exemplar = ExemplarOptions() if exemplar is None else exemplar
    omega = np.asarray(omega, bool)
    common = {"dtype": dtype, "progress": progress, "seed": seed}
    periodic = periodic_clusters(data, omega, periodicity)
    fill_spectral = load("spectral").solve
    if not periodic.any():
        return fill_spectral(data, omega, runtime, **common, **keywords(spectral))
    # the exemplar fills every hole (the others must not be copied from as if known) and
    # keeps its fill of the periodic clusters; the spectral fill does the rest from those
    out = load("exemplar").solve(data, omega, runtime, **common, **keywords(exemplar))
    out = np.asarray(out, np.float64)
    rest = omega & ~periodic
    if rest.any():
        out = np.asarray(
            fill_spectral(out, rest, runtime, **common, **keywords(spectral)), np.float64
        )
    return out

"""method="pick": the spectral fill, except where a cluster of damage sits in a periodic
pattern, which the exemplar copies instead, or in a smoothly varying surround, which the
biharmonic fill takes (and, with the smooth vote, where the biharmonic fill predicts a
hidden ring around a cluster better).

The spectral fill (spectral.py) leads on thin damage and photos but cannot continue a
periodic pattern across a hole of several periods (issue 37: 7.85 dB behind FSR-best on the
corpus's periodic class), where the exemplar copies it exactly. What decides is measured at
the hole, cheaply: for each cluster of damage (a connected component of the hole grown by
1 px) at least MIN_RADIUS px thick, the periodicity of the known pixels in a window of its
bounding box grown by WINDOW px (choose.repeat: the autocorrelation of the detail over
lags of 6-32 px, FFTs on the host, at its best lag and off the line through that lag: a
straight edge repeats along itself at every shift, a periodic pattern off that line too).
A cluster whose surround repeats at least as well as choose.MIN_PERIODICITY (the
exemplar's own threshold for copying without a structure guide) takes the exemplar's fill;
every other takes the spectral fill. (The largest autocorrelation alone, choose.periodicity,
sent blobs on straight edges to the exemplar: -0.42 dB on the test half's blobs.) A box
without such a cluster, or a routed one (below), is filled by the spectral fill alone,
exactly as method="spectral".

The smooth route (`route=True`, the default): a cluster at least ROUTE_RADIUS thick, not
periodic and not on a clear edge (edge_contrast), whose surround varies smoothly takes the
biharmonic fill, solved per cluster on the host (smooth.py: a direct sparse solve, a few
ms for a cluster of hundreds of pixels) before the spectral fill fills the rest, which
then reads those clusters as known. "Smoothly": the surround's roughness (`roughness`:
the RMS of the fine detail, grey minus its local mean, on the known pixels within 8 px,
over the standard deviation of the grey known pixels in the cluster's window) is below
ROUGH (both chosen on the calibration half: docs/inpainting.md, "A smooth route for smooth
surrounds"). Where the surround's variation is mostly at scales above the hole's border (a
smooth field), a smooth fill continues it, and the spectral fill's sparse Fourier model
adds detail that is not there; where fine detail dominates it, the spectral fill keeps
the cluster. Thinner clusters (3-6 px) in smooth surrounds lost on the calibration half's
blobs (-0.42 dB), rougher surrounds on its thick holes. What it costs: one distance
transform of the box and a window's standard deviation per cluster at least ROUTE_RADIUS
thick; the routed clusters' host fill replaces the spectral fill's work there.
A cluster whose window is piecewise smooth (depth.py: a depth map's flat or planar surfaces
and the jumps between them) is not routed: the biharmonic fill bends the surfaces across the
jumps, which the spectral fill continues as edges (calibration: rendered disparity maps).

The Gaussian-field route (part of `route`, before the smooth route): a cluster at least
MIN_RADIUS thick, not periodic and not on a clear edge, whose window is a Gaussian random
field (fields.py: neighbours' differences Gaussian at two scales, a power-law variogram)
takes the harmonic fill where the variogram's exponent is below 1 (a rough, fractal-like
field), the biharmonic fill above (a smooth one), both on the host per cluster: there the
spectral fill fits the field's fine detail as if it were structure (issue 37's voids).
Photos, microscopy and binned 16-bit data are not Gaussian fields: on the calibration half
it moves only the voids (23.99 -> 24.61 dB; docs/inpainting.md, "Voids in Gaussian
fields").

The smooth vote (`smooth=True`, off by default): each other cluster at least SMOOTH_RADIUS
thick and not on a clear edge (edge_contrast: its border splits into two sides of distinct
colour) is tested: a ring of RING known pixels around it is hidden, and the spectral
fill and the biharmonic fill predict it; where the biharmonic's error is below
SMOOTH_RATIO times the spectral's, the biharmonic fill takes the cluster. On the corpus
it gains on smooth fields and texture and ties elsewhere, but costs 3-4.3x the spectral
fill's CPU time on thick damage (2.3x / 2.6x over the calibration / test half), against a
budget of 1.2x: so it is opt-in. What it costs, each about the spectral fill's own time:
the spectral prediction of the ring (a fill of the holes grown by the ring, which a
cheaper fill misjudges: one block grid lost 0.35 dB on the calibration blobs, 20 picks
0.3 dB), and the biharmonic prediction (conjugate gradients, 300-1000 iterations of a few
launches each, which tol 1e-3 misjudged on a smooth field). Clusters on a
clear edge are left out because there the spectral fill, which continues the edge, beat
the biharmonic one on the calibration half (sending them to the biharmonic fill lost up
to 0.3 dB on the structure class).

Chosen on the calibration half of tests/cases/inpaint_corpus.py's corpus
(benchmarks/inpaint_default_route.py, from cached fills; benchmarks/inpaint_pick_time.py
runs it; docs/inpainting.md has both halves). A smooth route by the surround's texture
alone (the biharmonic fill where it has little) gained nothing at any threshold.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy import ndimage

from ..errors import InputError
from . import choose, depth, fields, poisson
from .exemplar import ExemplarOptions
from .registry import keywords, load, register
from .smooth import fill as smooth_fill
from .smooth import grown_box
from .spectral import MARGIN as SPECTRAL_MARGIN
from .spectral import SpectralOptions

# The spectral fill's program, which every call builds (the first use's notice,
# api._cold, reads it); the exemplar's and the biharmonic fill's only on some clusters.
KERNEL_FILES = ("inpainting/spectral.cl",)

DESCRIPTION = (
    "the spectral fill, the exemplar's where a cluster sits in a periodic pattern, and the "
    "biharmonic fill's on thick clusters in a smooth surround, the harmonic fill's on thick "
    "clusters in a rough Gaussian field"
)

MIN_RADIUS = 3.0  # thinner clusters: the spectral fill (a scratch needs no period copied)
WINDOW = 24  # px of surround measured around each cluster's bounding box
BORDER = 2  # px of known pixels around a cluster whose colours tell an edge crossing it
# The smooth vote (module docstring): a ring of RING px hidden around each thick cluster
# that is neither periodic nor on a clear edge (EDGE_GAP, EDGE_SEPARATION: edge_contrast);
# the biharmonic fill takes the cluster where its error on the ring is below SMOOTH_RATIO
# times the spectral fill's. Chosen on the calibration half
# (benchmarks/inpaint_default_route.py --rings): see the module docstring.
RING = 4
SMOOTH_RADIUS = 3.0  # the thinnest cluster tested (half-thickness, px)
SMOOTH_RATIO = 0.8
EDGE_GAP = 0.1
EDGE_SEPARATION = 3.0
# The ring test's spectral prediction takes 40 picks a block instead of 100 (profiled: the
# vote's time on thick damage was a second spectral fill, of the grown holes, a biharmonic
# solve of 300-1000 iterations and the chosen clusters' biharmonic fill, each about the
# first spectral fill's time; one block grid instead of two lost 0.35 dB on the calibration
# blobs). The biharmonic prediction stays at tol 1e-5: stopped at 1e-3 from the ring's mean
# it misjudged a smooth field's 15 px hole, and from the spectral prediction it saved 10%.
RING_SPECTRAL = {"iterations": 40}
# The smooth route (module docstring): a cluster at least ROUTE_RADIUS thick whose
# surround's roughness is below ROUGH goes to the host's biharmonic fill (smooth.py).
# Chosen on the calibration half (benchmarks/inpaint_smooth_route.py; docs/inpainting.md,
# "A smooth route"): thinner clusters or rougher surrounds lost on blobs and thick holes.
ROUGH = 0.15
ROUTE_RADIUS = 6.0
# A routed cluster of more hole pixels than this is solved on the device (poisson.py): the
# host's direct solve grows faster than its size (2,800 px: 0.02 s, 11,000: 0.17 s,
# 31,000: 1.3 s on the 2-core VM)
HOST_MAX = 12000
FINAL_TOL = 1e-3  # the chosen clusters' biharmonic fill, from the spectral fill


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
        A cluster whose surround repeats at least this well goes to the exemplar.
    smooth : bool
        Let the biharmonic fill take the thick clusters whose ring it predicts better
        (the smooth vote; False: the spectral fill keeps them).
    route : bool
        Give the thick clusters in a smoothly varying surround to the biharmonic fill (the
        smooth route; False: the spectral fill keeps them).
    """

    spectral: SpectralOptions = field(default_factory=SpectralOptions)
    exemplar: ExemplarOptions = field(default_factory=ExemplarOptions)
    periodicity: float = choose.MIN_PERIODICITY
    smooth: bool = False
    route: bool = True

    def __post_init__(self) -> None:
        if not isinstance(self.spectral, SpectralOptions):
            raise InputError(f"spectral must be SpectralOptions, not {self.spectral!r}")
        if not isinstance(self.exemplar, ExemplarOptions):
            raise InputError(f"exemplar must be ExemplarOptions, not {self.exemplar!r}")
        if not 0 <= self.periodicity <= 1:  # NaN too
            raise InputError(f"periodicity must be in [0, 1], not {self.periodicity!r}")
        if not isinstance(self.smooth, bool):
            raise InputError(f"smooth must be True or False, not {self.smooth!r}")
        if not isinstance(self.route, bool):
            raise InputError(f"route must be True or False, not {self.route!r}")


def clusters_of(omega):
    """The hole's clusters (components of the hole grown by 1 px, 8-connected): (labels,
    count, radius per cluster: its deepest hole pixel's distance to the known ones)."""
    # grown by 1 px: the hole and its 4-neighbours (the known pixels at distance 1)
    grown = ndimage.binary_dilation(omega, ndimage.generate_binary_structure(2, 1))
    clusters, count = ndimage.label(grown, np.ones((3, 3), bool))
    depth = ndimage.distance_transform_edt(omega)
    radius = np.zeros(count + 1)
    np.maximum.at(radius, clusters.ravel(), depth.ravel())  # (depth >= 0, known: 0)
    return clusters, count, radius[1:]


def has_thick(omega) -> bool:
    """Whether a pixel of omega lies at least MIN_RADIUS from every known pixel (the test
    of clusters_of's radius, without labelling: thin damage needs no periodicity test)."""
    r = int(np.ceil(MIN_RADIUS))
    y, x = np.mgrid[-r : r + 1, -r : r + 1]
    # the known pixels nearer than MIN_RADIUS (squared distances are whole numbers)
    near = y**2 + x**2 < MIN_RADIUS**2
    return bool(ndimage.binary_erosion(omega, near, border_value=1).any())


def periodic_clusters(data, omega, periodicity=choose.MIN_PERIODICITY, parts=None, detail=None):
    """The hole's pixels whose cluster sits in a periodic surround (module docstring): a
    bool mask, within omega. parts: clusters_of(omega), detail: choose._detail(data,
    ~omega), if already known."""
    omega = np.asarray(omega, bool)
    clusters, count, radius = clusters_of(omega) if parts is None else parts
    thick = np.flatnonzero(radius >= MIN_RADIUS)
    if not thick.size:
        return np.zeros_like(omega)
    detail, ok = choose._detail(data, ~omega) if detail is None else detail
    slices = ndimage.find_objects(clusters)
    chosen = []
    for k in thick:
        w = grown_box(slices[k], WINDOW, omega.shape)
        if choose.repeat(detail[w], ok[w]) >= periodicity:
            chosen.append(k + 1)
    return np.isin(clusters, chosen) & omega


def roughness(data, omega, parts, labels, detail=None):
    """Per cluster in `labels`, how much of its surround's variation is fine detail: the RMS
    of the detail (choose._detail) on the known pixels within choose.RING px that are
    nearest to it, over the standard deviation of the grey known pixels in its window (its
    box grown by WINDOW). Low: the surround varies smoothly (a smooth fill continues it);
    about 1: the surround is texture or noise at the scale of a few pixels."""
    omega = np.asarray(omega, bool)
    clusters = parts[0]
    known = ~omega
    d = (choose._detail(data, known) if detail is None else detail)[0]
    dist, (iy, ix) = ndimage.distance_transform_edt(known, return_indices=True)
    owner = np.where(known & (dist <= choose.RING), clusters[iy, ix], 0)
    energy = np.asarray(ndimage.mean(d.astype(np.float64) ** 2, owner, labels), float)
    grey = np.asarray(data, np.float64).mean(axis=0)
    slices = ndimage.find_objects(clusters)
    out = np.full(len(labels), np.inf)
    for i, lab in enumerate(labels):
        w = grown_box(slices[lab - 1], WINDOW, omega.shape)
        g = grey[w][known[w]]
        if g.size > 1 and np.isfinite(energy[i]):
            out[i] = np.sqrt(energy[i]) / max(float(g.std()), 1e-12)
    return out


def smooth_clusters(data, omega, parts, periodic, detail=None):
    """The labels of the clusters that the smooth route gives to the biharmonic fill
    (module docstring): at least ROUTE_RADIUS thick, not periodic, not on a clear edge, a
    surround of roughness below ROUGH, and not piecewise smooth (depth.py)."""
    clusters, count, radius = parts
    in_period = np.zeros(count + 1, bool)
    in_period[np.unique(clusters[periodic])] = True
    labels = 1 + np.flatnonzero((radius >= ROUTE_RADIUS) & ~in_period[1:])
    if not labels.size:
        return labels
    labels = labels[roughness(data, omega, parts, labels, detail) < ROUGH]
    if labels.size:
        # a clear edge across the hole: the spectral fill continues it, a smooth one blurs it
        gap, separation = edge_contrast(data, omega, parts, labels)
        edge = (gap >= EDGE_GAP) & (separation >= EDGE_SEPARATION)
        labels = labels[~edge[labels - 1]]
    if labels.size:
        # a piecewise-smooth surround (a depth map's surfaces and jumps): the spectral fill
        # continues the jumps, the biharmonic one bends the surfaces across them (depth.py)
        labels = np.setdiff1d(labels, depth.piecewise_smooth(data, omega, clusters, labels, WINDOW))
    return labels


def edge_contrast(data, omega, parts=None, labels=None):
    """Per cluster (label 1..count of clusters_of), how clearly its border splits into two
    sides of distinct colour: the border's known pixels (within BORDER px of the hole,
    each its nearest cluster's) projected on their colours' principal axis and split in
    two where the groups' means lie farthest apart for their size (Otsu's split). Returns
    two arrays: the gap between the groups' means (in data units), and that gap over the
    sum of the groups' standard deviations (about 1.7 for noise or a shading without
    sides); both 0 for a cluster with too few border pixels. A hole on an edge between two flat
    regions scores high; texture, and a gradient that merely shades across, low. parts:
    clusters_of(omega), if already known; labels: only these clusters are measured (the
    others score 0)."""
    omega = np.asarray(omega, bool)
    clusters, count, _ = clusters_of(omega) if parts is None else parts
    known = ~omega
    dist, (iy, ix) = ndimage.distance_transform_edt(known, return_indices=True)
    ring = known & (dist <= BORDER)
    owner = clusters[iy, ix][ring]
    values = np.asarray(data, np.float64)[:, ring]  # (c, m)
    order = np.argsort(owner, kind="stable")
    bounds = np.searchsorted(owner[order], np.arange(1, count + 2))
    gap, separation = np.zeros(count), np.zeros(count)
    for k in range(count) if labels is None else np.asarray(labels) - 1:
        v = values[:, order[bounds[k] : bounds[k + 1]]]
        if v.shape[1] < 8:
            continue
        v = v - v.mean(axis=1, keepdims=True)
        # the principal axis of the border's colours (the first left singular vector)
        axis = np.linalg.svd(v, full_matrices=False)[0][:, 0] if v.shape[0] > 1 else np.ones(1)
        t = np.sort(axis @ v)
        n = t.size
        i = np.arange(1, n)  # splits: t[:i] | t[i:]
        c1, c2 = np.cumsum(t)[:-1], t.sum() - np.cumsum(t)[:-1]
        m1, m2 = c1 / i, c2 / (n - i)
        j = int(np.argmax(i * (n - i) * (m2 - m1) ** 2))
        lo, hi = t[: j + 1], t[j + 1 :]
        gap[k] = hi.mean() - lo.mean()
        separation[k] = gap[k] / (lo.std() + hi.std() + 1e-6)
    return gap, separation


def _gaussian_route(data, omega, parts, periodic, runtime, dtype):
    """The clusters at least MIN_RADIUS thick, not periodic and not on a clear edge, whose
    surround is a Gaussian field (fields.py): (data with those of them that take the
    harmonic fill filled, the labels of them all, the labels left to the biharmonic fill)."""
    clusters, count, radius = parts
    in_period = np.zeros(count + 1, bool)
    in_period[np.unique(clusters[periodic])] = True
    labels = 1 + np.flatnonzero((radius >= MIN_RADIUS) & ~in_period[1:])
    none = np.zeros(0, int)
    if not labels.size:
        return data, none, none
    rough, smooth = fields.gaussian_clusters(data, omega, clusters, labels, WINDOW)
    both = np.union1d(rough, smooth)
    if not both.size:
        return data, none, none
    # a clear edge across the hole: the spectral fill continues it (as the smooth route)
    gap, separation = edge_contrast(data, omega, parts, both)
    edge = 1 + np.flatnonzero((gap >= EDGE_GAP) & (separation >= EDGE_SEPARATION))
    rough, smooth = np.setdiff1d(rough, edge), np.setdiff1d(smooth, edge)
    if rough.size:
        size = np.bincount(clusters[omega], minlength=count + 1)[rough]
        data = smooth_fill(data, omega, clusters, rough[size <= HOST_MAX], order=1)
        if (size > HOST_MAX).any():  # (the device's solve, as the smooth route's)
            big = np.isin(clusters, rough[size > HOST_MAX]) & omega
            data = poisson.fill(data, big, runtime, "harmonic", dtype=dtype)
            data = np.asarray(data, np.float64)
    return data, np.union1d(rough, smooth), smooth


def _margin(omega, o: PickOptions) -> int:
    # the spectral fill's boxes, so that a box without a periodic cluster is filled
    # exactly as method="spectral" fills it; the exemplar searches the box
    return SPECTRAL_MARGIN(omega, o.spectral.block, o.spectral.border)


def _ring_test(filled, omega, clusters, labels, runtime, common, spectral):
    """The labels among `labels` whose ring (the known pixels within RING px, each its
    nearest cluster's) the biharmonic fill predicts better than SMOOTH_RATIO times the
    spectral fill does, both filling the clusters and their rings hidden at once in
    `filled` (the box with every hole filled, so that the other clusters cost nothing).
    The spectral prediction is cheaper than the fill it stands for (RING_SPECTRAL): the
    vote needs the ratio of the errors, not their last digits."""
    known = ~omega
    dist, (iy, ix) = ndimage.distance_transform_edt(known, return_indices=True)
    owner = np.where(known & (dist <= RING), clusters[iy, ix], 0)
    ring = np.isin(owner, labels)
    if not ring.any() or not (known & ~ring).any():
        return []
    hidden = ring | (np.isin(clusters, labels) & omega)
    truth = filled[:, ring]
    errors = []
    quick = {**keywords(spectral), **RING_SPECTRAL}
    guess = load("spectral").solve(filled, hidden, runtime, **common, **quick)
    guess = np.asarray(guess, np.float64)
    smooth = poisson.fill(filled, hidden, runtime, "biharmonic", dtype=common["dtype"])
    for out in (guess, np.asarray(smooth, np.float64)):
        sq = ((out[:, ring] - truth) ** 2).sum(axis=0)
        errors.append(ndimage.sum(sq, owner[ring], labels))
    spectral_error, smooth_error = (np.asarray(e, float).reshape(-1) for e in errors)
    return [
        lab
        for lab, a, b in zip(labels, spectral_error, smooth_error, strict=True)
        if b < SMOOTH_RATIO * a
    ]


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
    smooth=False,
    route=True,
):
    """The picked fill of one box (module docstring; registry.py's protocol)."""
    spectral = SpectralOptions() if spectral is None else spectral
    exemplar = ExemplarOptions() if exemplar is None else exemplar
    omega = np.asarray(omega, bool)
    common = {"dtype": dtype, "progress": progress, "seed": seed}
    parts = clusters_of(omega) if smooth or has_thick(omega) else None
    detail = None if parts is None else choose._detail(data, ~omega)
    periodic = (
        np.zeros_like(omega)
        if parts is None
        else periodic_clusters(data, omega, periodicity, parts, detail)
    )
    routed = np.zeros(1 if parts is None else parts[1] + 1, bool)
    rest = omega
    if route and parts is not None:
        data, gauss, labels = _gaussian_route(data, omega, parts, periodic, runtime, dtype)
        labels = np.union1d(
            labels, np.setdiff1d(smooth_clusters(data, omega, parts, periodic, detail), gauss)
        )
        routed[gauss] = True
        if labels.size:
            # the smooth clusters first: the spectral fill then reads them as known
            size = np.bincount(parts[0][omega], minlength=parts[1] + 1)[labels]
            data = smooth_fill(data, omega, parts[0], labels[size <= HOST_MAX])
            if (size > HOST_MAX).any():  # (the device's solve: its stencil reads only known
                # pixels and the cluster's own, clusters being 3 px apart)
                big = np.isin(parts[0], labels[size > HOST_MAX]) & omega
                data = np.asarray(poisson.fill(data, big, runtime, dtype=dtype), np.float64)
            routed[labels] = True
        rest = omega & ~routed[parts[0]]
    fill_spectral = load("spectral").solve
    if not rest.any():
        out = data
    elif not periodic.any():
        out = fill_spectral(data, rest, runtime, **common, **keywords(spectral))
    else:
        # the exemplar fills every hole (the others must not be copied from as if known)
        # and keeps its fill of the periodic clusters; the spectral fill does the rest
        out = load("exemplar").solve(data, rest, runtime, **common, **keywords(exemplar))
        others = rest & ~periodic
        if others.any():
            out = fill_spectral(
                np.asarray(out, np.float64), others, runtime, **common, **keywords(spectral)
            )
    if not smooth:
        return out
    clusters, count, radius = parts
    in_period = np.zeros(count + 1, bool)
    in_period[np.unique(clusters[periodic])] = True
    candidates = (radius >= SMOOTH_RADIUS) & ~in_period[1:] & ~routed[1:]
    if not candidates.any():  # (thin damage: no edge test, no ring test)
        return out
    gap, separation = edge_contrast(data, omega, parts)
    edge = (gap >= EDGE_GAP) & (separation >= EDGE_SEPARATION)
    labels = 1 + np.flatnonzero(candidates & ~edge)
    if not labels.size:
        return out
    out = np.asarray(out, np.float64)
    chosen = _ring_test(out, omega, clusters, labels, runtime, common, spectral)
    if chosen:
        hole = np.isin(clusters, chosen) & omega
        out = poisson.fill(out, hole, runtime, dtype=dtype, start=out, tol=FINAL_TOL)
        out = np.asarray(out, np.float64)
    return out

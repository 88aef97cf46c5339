"""Decoy holes: `method="auto"`'s vote on copies of each cluster of damage's own shape,
placed on known pixels nearby, instead of on rings hidden around it (issue 37). Measured
and not taken: benchmarks/inpaint_vote_sound.py --real --vote decoys runs `choose` here in
auto.choose's place (docs/inpainting.md, "Decoys of the hole's own shape").

A ring of known pixels hidden around a hole tests a fill at the ring's depth, not at the
hole's: a thin ring rewards the fills that are good next to the border, a wide one makes
the hole thicker than it is. A copy of the hole's own shape, moved onto known pixels
nearby, has the hole's thickness at every pixel, so every candidate's error on it is a
sample of its error in the hole itself, whatever the shape.

Each copy is the cluster's hole pixels translated on a grid of steps one cluster size plus
GAP apart (nearest first, within WINDOW cluster sizes but at least MIN_WINDOW px), kept
where at least KEEP of its pixels land on known pixels more than GAP px from the damage,
from the box's edge and from every decoy placed before (the pixels that do not are
dropped: a long scratch or a crack network cannot be copied whole, but its thickness can).
"""

from __future__ import annotations

import numpy as np
from scipy import ndimage, optimize

from clpde.errors import InputError
from clpde.inpainting import auto

# Decoys per cluster, chosen on the calibration half (8: 12 of 62 cases below the bound,
# 4.47 dB in all; 4: 14, 9.65 dB; 12: 10, but periodic-4 -34 dB).
COUNT = 8
# Known pixels between a decoy and the damage, the box's edge or another decoy.
GAP = 3
# How far decoys may lie from their cluster, in cluster sizes (its bounding box's longer
# side), and at least MIN_WINDOW px: near enough to share its surroundings.
WINDOW = 4
MIN_WINDOW = 32
# The surround whose detail a decoy's should match: RING px around the shape (less the
# first, whose differences read the damage); FLOOR: detail added before the ratio (an
# 8-bit step's square), so that flat surroundings match each other.
RING = 4
FLOOR = (1 / 255) ** 2
# The least share of a cluster's pixels a decoy keeps (the rest land on damage or off
# the box).
KEEP = 0.5
# A cluster that no decoy can copy KEEP of (a crack network across the image) takes
# copies that keep at least LAST of it: its thickness, at least, is the hole's.
LAST = 0.1


def _offsets(h, w, reach):
    """Grid translations (dy, dx) of a (h, w) shape, steps h + GAP + 1 and w + GAP + 1 (so
    that copies on the grid never touch), within `reach` px, nearest first, (0, 0) out."""
    sy, sx = h + GAP + 1, w + GAP + 1
    ky, kx = reach // sy, reach // sx
    iy, ix = np.mgrid[-ky : ky + 1, -kx : kx + 1]
    dy, dx = (iy * sy).ravel(), (ix * sx).ravel()
    order = np.argsort(np.hypot(dy, dx), kind="stable")[1:]  # the first is (0, 0)
    return dy[order], dx[order]


def detail(data, omega):
    """Each pixel's detail: its squared gradient (central differences), summed over the
    channels; NaN where a difference reads the damage."""
    g = sum(sum(d**2 for d in np.gradient(c)) for c in np.asarray(data, np.float64))
    return np.where(ndimage.binary_dilation(omega), np.nan, g)


def _surround(ys, xs, shape):
    """The pixels within RING px of (ys, xs) but not within 1 px, as coordinates."""
    near = _grown(ys, xs, shape, 1)
    return np.nonzero(_grown(ys, xs, shape, RING) & ~near)


def _mean(values, y, x):
    """The mean of `values` at (y, x) inside it, NaN where none (or all NaN)."""
    ny, nx = values.shape
    inside = (y >= 0) & (y < ny) & (x >= 0) & (x < nx)
    v = values[y[inside], x[inside]]
    v = v[np.isfinite(v)]
    return float(v.mean()) if v.size else np.nan


def place(omega, labels, order, count=COUNT, texture=None):
    """Decoys of the clusters `order` (labels of the hole's pixels in `labels`, an int
    image), tried in that order: a label image (0: no decoy), each decoy pixel labelled
    with its cluster, and the decoys' own index per pixel (1, 2, ... within its cluster).
    With `texture` (`detail`'s map), the places whose surround's mean detail is nearest
    the cluster's (in ratio) come first, else the nearest places.

    Decoys never touch the damage, the edge of the image or each other: every decoy pixel
    lies more than GAP px from each (module docstring)."""
    ny, nx = omega.shape
    free = ndimage.distance_transform_edt(~omega) > GAP
    free[: GAP + 1], free[ny - GAP - 1 :] = False, False
    free[:, : GAP + 1], free[:, nx - GAP - 1 :] = False, False
    owner = np.zeros(omega.shape, np.int64)
    index = np.zeros(omega.shape, np.int64)
    objects = ndimage.find_objects(np.where(omega, labels, 0))
    for lab in order:
        if lab > len(objects) or objects[lab - 1] is None:
            continue
        sl = objects[lab - 1]
        ly, lx = np.nonzero((labels[sl] == lab) & omega[sl])
        ys, xs = ly + sl[0].start, lx + sl[1].start
        h, w = int(ly.max()) + 1, int(lx.max()) + 1
        reach = max(WINDOW * max(h, w), MIN_WINDOW)
        placed = 0
        dys, dxs = _offsets(h, w, reach)
        if texture is not None:  # surroundings like the cluster's first
            ry, rx = _surround(ys, xs, omega.shape)
            own = _mean(texture, ry, rx)
            cost = np.array([_mean(texture, ry + a, rx + b) for a, b in zip(dys, dxs, strict=True)])
            cost = np.abs(np.log((cost + FLOOR) / (own + FLOOR)))
            rank = np.argsort(np.where(np.isfinite(cost), cost, np.inf), kind="stable")
            dys, dxs = dys[rank], dxs[rank]
        for keep in (KEEP, LAST):  # LAST: only where no decoy kept KEEP
            for dy, dx in zip(dys, dxs, strict=True):
                if placed == count:
                    break
                y, x = ys + dy, xs + dx
                inside = (y >= 0) & (y < ny) & (x >= 0) & (x < nx)
                ok = inside.copy()
                ok[inside] = free[y[inside], x[inside]]
                if ok.sum() < max(keep * ys.size, 1):
                    continue
                y, x = y[ok], x[ok]
                placed += 1
                owner[y, x], index[y, x] = lab, placed
                # no later decoy within GAP px of this one
                free[_grown(y, x, omega.shape, GAP)] = False
            if placed:
                break
    return owner, index


def _grown(ys, xs, shape, by):
    """The pixels (ys, xs) grown by `by` px (Euclidean), as a mask of `shape`: a distance
    transform over their bounding box only."""
    y0, x0 = max(int(ys.min()) - by, 0), max(int(xs.min()) - by, 0)
    y1 = min(int(ys.max()) + by + 1, shape[0])
    x1 = min(int(xs.max()) + by + 1, shape[1])
    local = np.ones((y1 - y0, x1 - x0), bool)
    local[ys - y0, xs - x0] = False
    out = np.zeros(shape, bool)
    out[y0:y1, x0:x1] = ndimage.distance_transform_edt(local) <= by
    return out


# The vote (what auto.choose does with rings, here with decoys): a cluster's weights are
# its own decoys' least-squares blend pulled towards the box's, as if the box's decoys added
# PRIOR values to the cluster's own; a blend giving one candidate at least SNAP is that
# candidate alone (blending an exact fill, a periodic pattern's exemplar, costs far more
# than it gains). Where no decoy fits at all, DEFAULT fills.
PRIOR = 1000.0
SNAP = 0.8
DEFAULT = "spectral"


def _weights(fills, truth):
    """Non-negative weights summing to one that minimise |sum_k w_k fills_k - truth|^2
    (fills: (k, n), truth: (n,)); a candidate whose fills are NaN (it could not fill the
    decoys) gets none."""
    ok = np.isfinite(fills[:, 0]) if fills.shape[1] else np.ones(fills.shape[0], bool)
    if not ok.all():
        w = np.zeros(fills.shape[0])
        w[ok] = _weights(fills[ok], truth)
        return w
    k = fills.shape[0]
    if k == 1:
        return np.ones(1)
    # eliminate the sum constraint: w_last = 1 - sum(others); bounded least squares
    res = optimize.lsq_linear((fills[:-1] - fills[-1]).T, truth - fills[-1], bounds=(0, 1))
    w = np.clip(np.append(res.x, 1 - res.x.sum()), 0, None)  # the bounds allow a sum > 1
    return w / w.sum()


def _decoy_tests(names, data, omega, owner, runtime, dtype, seed, params):
    """Every candidate's fill of the decoys (the hole hidden too, as in its own fill), the
    true values there and each value's cluster: (k, n), (n,), (n,) over pixels and
    channels; NaN for a candidate that cannot fill them (an exemplar left without whole
    patches to copy), which the vote then leaves out."""
    test = owner > 0
    hidden = omega | test
    fills = []
    for n in names:
        try:
            fills.append(auto._fill(n, data, hidden, runtime, dtype, seed, params)[:, test])
        except InputError:
            fills.append(np.full((data.shape[0], int(test.sum())), np.nan))
    lab = np.broadcast_to(owner[test], (data.shape[0], int(test.sum())))
    return np.stack([f.reshape(-1) for f in fills]), data[:, test].reshape(-1), lab.reshape(-1)


def _vote(names, tests, lab, prior, box, snap):
    """One cluster's weights from the decoys (PRIOR and SNAP above): its own decoys' blend
    pulled towards the box's (`box`) by `prior` values; the box's alone where it has no
    decoy; a blend within SNAP of one candidate is that candidate. (weights, why, RMS
    error of each candidate on its decoys or None)."""
    fills, truth, of = tests
    mine = of == lab
    if not mine.any():
        w, why, rmse = box, "the box's decoys", None
    else:
        f, t = fills[:, mine], truth[mine]
        w = _weights(f, t)
        w = box if np.isinf(prior) else (t.size * w + prior * box) / (t.size + prior)
        why, rmse = "decoy vote", np.sqrt(((f - t) ** 2).mean(axis=1))  # NaN: no fill
    if w.max() >= snap:
        w = np.eye(len(names))[int(np.argmax(w))]
    return w, why, rmse


def choose(
    data,
    omega,
    runtime,
    *,
    names=None,
    decoys: int | None = None,
    prior: float | None = None,
    snap: float | None = None,
    thin: float = 0.0,
    dtype=np.float32,
    seed=None,
    params=None,
):
    """Fill omega in data ((channels, rows, cols) in [0, 1]) by the self-validated choice
    among the candidates, voted on decoys (module docstring; auto.choose's protocol).

    Returns (filled, report): filled has data's shape, equal to data outside omega;
    report is {"candidates": [...], "choices": [{"pixels", "why", "weights", "chosen",
    "decoy_rmse"} per cluster], "decoy_pixels": int}.
    """
    params = params or {}
    decoys = COUNT if decoys is None else decoys
    prior = PRIOR if prior is None else prior
    snap = SNAP if snap is None else snap
    omega = np.asarray(omega, bool)
    names = auto.candidates(names)
    fills = {n: auto._fill(n, data, omega, runtime, dtype, seed, params) for n in names}
    known = ~omega
    dist = ndimage.distance_transform_edt(known)  # 0 in the hole
    clusters, count = ndimage.label(dist <= 1, np.ones((3, 3), bool))
    out = np.array(data, np.float64, copy=True)
    stack = np.stack([fills[n][:, omega] for n in names])  # (k, c, n): the hole's fills
    hole_label = clusters[omega]
    members = auto._groups(hole_label, count)
    depth = ndimage.distance_transform_edt(omega)  # each hole pixel's half-thickness
    radius = np.asarray(ndimage.maximum(depth, clusters, np.arange(1, count + 1))).reshape(-1)
    choices, vote = auto._settled(names, stack, members, radius, thin, count)
    decoy_pixels = 0
    if vote.any():
        voting = np.flatnonzero(vote)
        order = voting[np.argsort([-members[lab].size for lab in voting], kind="stable")]
        texture = detail(data, omega)
        owner, index = place(omega, clusters, order, decoys, texture)
        check(omega, owner, index, decoys)
        decoy_pixels = int((owner > 0).sum())
        tests = None
        if decoy_pixels and (known & (owner == 0)).any():
            tests = _decoy_tests(names, data, omega, owner, runtime, dtype, seed, params)
            box = _weights(tests[0], tests[1])  # every voting cluster's decoys at once
        for lab in voting:
            pixels = int(members[lab].size)
            if tests is None:
                k = names.index(DEFAULT) if DEFAULT in names else len(names) - 1
                w, why, rmse = np.eye(len(names))[k], "no decoy fits", None
            else:
                w, why, rmse = _vote(names, tests, lab, prior, box, snap)
            choices[lab - 1] = {
                "pixels": pixels,
                "why": why,
                "chosen": names[int(np.argmax(w))],
                "weights": {n: float(x) for n, x in zip(names, w, strict=True) if x > 0},
            }
            if rmse is not None:
                choices[lab - 1]["decoy_rmse"] = dict(zip(names, rmse.tolist(), strict=True))
    out[:, omega] = auto._assemble(names, choices, count, hole_label, stack)
    report = {
        "candidates": names,
        "decoy_pixels": decoy_pixels,
        "choices": [c for c in choices if c is not None],
    }
    return out, report


def check(omega, owner, index, count=COUNT):
    """Raise AssertionError unless the decoys (place's owner, index) keep more than GAP px
    from the damage, the image's edge and each other, at most `count` per cluster; every
    vote here runs it."""
    test = owner > 0
    if not test.any():
        return
    ny, nx = omega.shape
    assert not test[omega].any(), "a decoy on the damage"
    assert ndimage.distance_transform_edt(~omega)[test].min() > GAP, "a decoy by the damage"
    ys, xs = np.nonzero(test)
    assert min(ys.min(), xs.min(), ny - 1 - ys.max(), nx - 1 - xs.max()) > GAP, "by the edge"
    key = owner * (int(index.max()) + 1) + index
    assert np.unique(key[test]).size <= count * np.unique(owner[test]).size
    for a in np.unique(key[test]):
        near = ndimage.distance_transform_edt(key != a)[test & (key != a)]
        assert not near.size or near.min() > GAP, "two decoys touch"


def main():
    """Self-checks (tests/ may not import benchmarks/): the placement's rules on a disc, a
    long scratch and specks, and the vote's choice where one candidate is clearly best:
    vertical stripes of period 6 (only the exemplar copies them) and a slow smooth wave on a
    ramp (the biharmonic fill is nearly exact)."""
    from clpde.runtime import get_runtime

    rng = np.random.default_rng(2)
    y, x = np.mgrid[0:120, 0:150]
    omega = np.hypot(y - 40, x - 60) <= 8
    omega[90:92, 10:140] = True
    omega[rng.integers(0, 120, 12), rng.integers(0, 150, 12)] = True
    labels, count = ndimage.label(ndimage.distance_transform_edt(~omega) <= 1, np.ones((3, 3)))
    owner, index = place(omega, labels, list(range(1, count + 1)))
    check(omega, owner, index)
    disc = omega & (labels == labels[40, 60])
    kept = [((owner == labels[40, 60]) & (index == i)).sum() for i in range(1, COUNT + 1)]
    assert max(kept) == disc.sum() and min(kept) >= KEEP * disc.sum(), kept
    print(f"placement: {np.unique(owner * 100 + index).size - 1} decoys of {count} clusters ok")
    y, x = np.mgrid[0:96, 0:96]
    mask = np.hypot(y - 48, x - 48) <= 6
    names = ("biharmonic", "exemplar", "spectral")
    for image, best in (
        (0.2 + 0.6 * ((x % 6) < 3), "exemplar"),
        (0.3 + 0.2 * np.sin(x / 9) * np.cos(y / 11) + 0.2 * y / 96, "biharmonic"),
    ):
        _, report = choose(image[None], mask, get_runtime(), names=names, seed=0)
        (c,) = report["choices"]
        assert c["why"] == "decoy vote" and c["chosen"] == best, c
        print(f"{best}: chosen ({c['weights']})")


if __name__ == "__main__":
    main()

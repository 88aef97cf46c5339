"""A part's turn and shift, three parameters (issue 35, trackfoot): turns.py fitted each
part of the shape with appearance._refine's six affine parameters; on a part of a few
hundred pixels with its rim, six parameters can also shear and scale it onto its ring of
ground. Here the map is a rotation about the part's centre and a shift, fitted by
Gauss-Newton on the same grey levels and gradients."""

from __future__ import annotations

import numpy as np
from scipy import ndimage

from .appearance import bilinear, gradients


def rigid_fit(prev, cur, use, d, steps, grey=None, limit=0.5):
    """The map (2 x 3, cur -> prev coordinates, appearance's convention) of prev's pixels
    `use` onto cur: a turn about their centre and a shift, from the whole-pixel shift d
    (Gauss-Newton, `steps` steps); the shift alone where the turn fails (no better cost, a
    turn beyond `limit` radians). `grey`: prev's appearance.gradients and cur's grey level
    (H, W), or None."""
    stack, gc = grey if grey is not None else (gradients(prev), cur.mean(axis=0))
    d = np.asarray(d, np.float64)
    shifted = np.array([[1.0, 0.0, -d[0]], [0.0, 1.0, -d[1]]])
    h, w = use.shape
    rows = np.clip(np.arange(h) - int(round(d[0])), 0, h - 1)
    cols = np.clip(np.arange(w) - int(round(d[1])), 0, w - 1)
    where = use[np.ix_(rows, cols)]  # cur's pixels where the shift puts the part
    if where.sum() < 12:
        return shifted
    pts = np.array(np.nonzero(where), np.float64)
    centre = np.array(ndimage.center_of_mass(where))  # cur's coordinates
    q = pts - centre[:, None]

    def mapping(theta, s):
        c, n = np.cos(theta), np.sin(theta)
        lin = np.array([[c, -n], [n, c]])
        return np.column_stack([lin, centre + s - lin @ centre])

    def at(a, k=1):
        return bilinear(stack[:k], np.tensordot(a[:, :2], pts, 1) + a[:, 2:])

    # cur's grey levels mapped onto prev's by the gain and offset (a flicker is no motion)
    target = gc[where]
    ref = at(shifted)[0]
    target = (target - target.mean()) * (ref.std() / max(target.std(), 1e-6)) + ref.mean()
    start = float(np.mean((ref - target) ** 2))
    theta, s = 0.0, -d.copy()
    for _ in range(steps):
        a = mapping(theta, s)
        r, gy, gx = at(a, 3)
        r = r - target
        c, n = np.cos(theta), np.sin(theta)
        # d(A p)/d theta = R'(theta) (p - centre)
        dy, dx = -n * q[0] - c * q[1], c * q[0] - n * q[1]
        jac = np.column_stack([gy * dy + gx * dx, gy, gx])
        jtj = jac.T @ jac
        jtj += 1e-3 * np.trace(jtj) / 3 * np.eye(3)
        step = np.linalg.solve(jtj, -jac.T @ r)
        theta, s = theta + step[0], s + step[1:]
        if abs(step[0]) < 1e-3 and np.abs(step[1:]).max() < 0.02:
            break
    a = mapping(theta, s)
    ok = np.all(np.isfinite(a)) and abs(theta) <= limit
    return a if ok and float(np.mean((at(a)[0] - target) ** 2)) < start else shifted

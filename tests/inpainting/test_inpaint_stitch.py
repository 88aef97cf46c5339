"""Gradient-domain stitching of an exemplar fill (clpde.inpainting.stitch): the vote's
sources against the vote kernel's NumPy reference, and the Poisson system against a dense
solve of the same equations written out pixel by pixel."""

import numpy as np
from scipy import ndimage

from clpde.inpainting import patchmatch, stitch
from tests.reference import patchmatch as ref


def _dense_stitch(img, hole, src, offy, offx, r):
    """The same discrete scheme, one equation per hole pixel, solved densely."""
    nc, H, W = img.shape
    holes = list(zip(*np.nonzero(hole), strict=False))
    index = {p: k for k, p in enumerate(holes)}
    n = len(holes)
    A = np.zeros((n, n))
    b = np.zeros((nc, n))

    def known(y, x):
        return 0 <= y < H and 0 <= x < W and not hole[y, x]

    for k, (py, px) in enumerate(holes):
        s = src[k]
        for dy, dx in ((0, -1), (0, 1), (-1, 0), (1, 0)):
            qy, qx = py + dy, px + dx
            if not (0 <= qy < H and 0 <= qx < W):
                continue
            A[k, k] += 1
            views = {"any": [], "in": []}
            if s >= 0 and known(s // W + dy, s % W + dx):
                v = img[:, s // W, s % W] - img[:, s // W + dy, s % W + dx]
                views["any"].append(v)
                if abs(offy[k] + dy) <= r and abs(offx[k] + dx) <= r:
                    views["in"].append(v)
            if hole[qy, qx]:
                kq = index[(qy, qx)]
                t = src[kq]
                if t >= 0 and known(t // W - dy, t % W - dx):
                    v = img[:, t // W - dy, t % W - dx] - img[:, t // W, t % W]
                    views["any"].append(v)
                    if abs(offy[kq] - dy) <= r and abs(offx[kq] - dx) <= r:
                        views["in"].append(v)
                A[k, kq] -= 1
            else:
                b[:, k] += img[:, qy, qx]
            use = views["in"] or views["any"]
            b[:, k] += np.mean(use, 0) if use else img[:, py, px] - img[:, qy, qx]
    out = img.astype(np.float64).copy()
    for c in range(nc):
        sol = np.linalg.solve(A, b[c])
        for k, (py, px) in enumerate(holes):
            out[c, py, px] = sol[k]
    return out


def _level(runtime, seed=4):
    rng = np.random.default_rng(seed)
    shape = (22, 25)
    img = ndimage.gaussian_filter(rng.random((2,) + shape), (0, 1.5, 1.5))
    hole = np.zeros(shape, bool)
    hole[7:14, 8:16] = True
    hole[17:, 21:] = True  # touches two borders
    lv = patchmatch.PatchMatchLevel(runtime, np.float32, img, hole, [1.0, 1.0], 5, confidence=1.3)
    lv.random_nnf(rng)
    lv.score()
    return lv, img, hole


def test_vote_sources_are_what_the_best_only_vote_copies(runtime):
    lv, img, hole = _level(runtime)
    nnf, dist = lv.nnf_to_host(), lv.dist.get().reshape(hole.shape)
    pen = lv.pen.get().reshape(hole.shape)
    src, _, _ = stitch.vote_sources(nnf, dist, pen, hole, lv.r, 0.05)
    want = ref.vote(
        img,
        nnf,
        dist,
        hole,
        lv.r,
        0.05,
        True,
        None,
        ndimage.distance_transform_edt(hole) * np.log(1.3),
    )
    assert (src >= 0).all()
    np.testing.assert_allclose(img.reshape(2, -1)[:, src], want[:, hole], rtol=1e-6)


def test_stitch_matches_the_dense_reference(runtime):
    lv, img, hole = _level(runtime)
    nnf, dist = lv.nnf_to_host(), lv.dist.get().reshape(hole.shape)
    sources = stitch.vote_sources(nnf, dist, lv.pen.get().reshape(hole.shape), hole, lv.r, 0.05)
    filled = img.copy()
    filled[:, hole] = img.reshape(2, -1)[:, sources[0]]
    got = stitch.stitch(filled, hole, sources, lv.r)
    want = _dense_stitch(filled, hole, *sources, lv.r)
    np.testing.assert_allclose(got, want, rtol=1e-9, atol=1e-12)
    assert np.array_equal(got[:, ~hole], filled[:, ~hole])


def test_a_tone_jump_is_removed_and_exact_copies_stay():
    # A smooth image copied by a shift of one period: each hole pixel's source is the pixel
    # a period away. A fill offset by 0.2 (a seam at the hole's border) comes back exact.
    y, x = np.mgrid[0:40, 0:60]
    img = (0.5 + 0.3 * np.sin(2 * np.pi * x / 20) * np.cos(2 * np.pi * y / 20))[None]
    hole = np.zeros((40, 60), bool)
    hole[12:26, 30:46] = True
    py, px = np.nonzero(hole)
    src = py * 60 + px - 20
    zeros = np.zeros(src.size, np.int64)
    exact = stitch.stitch(img, hole, (src, zeros, zeros), 3)
    np.testing.assert_allclose(exact, img, atol=1e-12)
    jumped = img.copy()
    jumped[:, hole] += 0.2
    np.testing.assert_allclose(stitch.stitch(jumped, hole, (src, zeros, zeros), 3), img, atol=1e-12)

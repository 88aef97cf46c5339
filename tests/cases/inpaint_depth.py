"""More calibration cases for the inpainting corpus: disparity maps of rendered scenes.

    python benchmarks/inpaint_generalise.py --half calibration --more

The corpus's test half holds three disparity maps (the stereo motorcycle's: piecewise smooth
depth with jumps at the objects' outlines), and its calibration half none, so no rule for
such surfaces could be chosen honestly (docs/inpainting.md, "Depth maps"). These cases are
rendered here, by casting one ray per pixel from a pinhole camera into a scene of a few
primitives (a tilted ground plane, a back wall, boxes turned about the vertical, spheres) at
poses drawn from a fixed seed: the disparity f B / z is planar across each flat face,
curved across each sphere and jumps at every outline, as a stereo pair's is. Float32 and
uint16 versions (over the map's range, as the corpus's disparity-uint16), damaged by the
corpus's own voids and blobs. Every case is on the calibration half, whatever its name; no
sample image of any library is used.
"""

from __future__ import annotations

import numpy as np

from . import inpaint_corpus as corpus

SCENES = 6  # scenes 0-3 as float32, 4-5 as uint16
FOCAL, BASELINE = 1.1, 40.0  # focal length in image widths; disparity = FOCAL * BASELINE / z


def _rays(size):
    c = (np.arange(size) + 0.5) / size - 0.5
    x, y = np.meshgrid(c, c)
    d = np.stack([x, y, np.full_like(x, FOCAL)])
    return d / np.linalg.norm(d, axis=0)


def _plane(d, point, normal):
    normal = np.asarray(normal, float) / np.linalg.norm(normal)
    den = np.tensordot(normal, d, 1)
    with np.errstate(divide="ignore", invalid="ignore"):
        t = np.dot(normal, point) / den
    return np.where(t > 0, t, np.inf)


def _sphere(d, centre, radius):
    centre = np.asarray(centre, float)
    b = np.tensordot(centre, d, 1)
    disc = b * b - (centre @ centre - radius * radius)
    t = b - np.sqrt(np.maximum(disc, 0))
    return np.where((disc > 0) & (t > 0), t, np.inf)


def _box(d, centre, half, yaw):
    """A box of half-sides `half`, turned by `yaw` about the vertical (slab test)."""
    c, s = np.cos(yaw), np.sin(yaw)
    turn = np.array([[c, 0, -s], [0, 1, 0], [s, 0, c]])  # world -> box axes
    o = -turn @ np.asarray(centre, float)
    dd = np.tensordot(turn, d, 1)
    with np.errstate(divide="ignore", invalid="ignore"):
        lo = (-np.asarray(half)[:, None, None] - o[:, None, None]) / dd
        hi = (np.asarray(half)[:, None, None] - o[:, None, None]) / dd
    near = np.minimum(lo, hi).max(axis=0)
    far = np.maximum(lo, hi).min(axis=0)
    return np.where((near <= far) & (near > 0), near, np.inf)


def scene(seed, size=corpus.CROP):
    """The disparity map (float32) of scene `seed`: the ground, a wall and 4-8 objects."""
    rng = np.random.default_rng(corpus._seed("depth-scene", seed))
    d = _rays(size)
    tilt = rng.uniform(-0.15, 0.15)
    hits = [
        _plane(d, (0, rng.uniform(1.0, 1.6), 0), (tilt, -1, rng.uniform(0.05, 0.3))),
        _plane(d, (0, 0, rng.uniform(9, 14)), (rng.uniform(-0.4, 0.4), 0.1, -1)),
    ]
    for _ in range(rng.integers(4, 9)):
        z = rng.uniform(2.5, 8)
        x, y = rng.uniform(-0.45, 0.45) * z / FOCAL, rng.uniform(-0.3, 0.45) * z / FOCAL
        if rng.random() < 0.5:
            half = rng.uniform(0.04, 0.9, 3) * np.array([1, 1.6, 1])  # bars as well as blocks
            hits.append(_box(d, (x, y, z), half, rng.uniform(0, np.pi)))
        else:
            hits.append(_sphere(d, (x, y, z), rng.uniform(0.3, 1.0)))
    t = np.min(hits, axis=0)
    t = np.where(np.isfinite(t), t, 20.0)
    return (FOCAL * size * BASELINE / (t * d[2]) / size).astype(np.float32)


def sources():
    """[(source, image name, truth, kind, classes)], as inpaint_corpus.sources()."""
    out = []
    for k in range(SCENES):
        disp = scene(k)
        if k < 4:
            out.append((f"scene{k}", f"scene-float-{k}", disp, "float", ("voids", "blobs")))
        else:
            out.append((f"scene{k}", f"scene-uint16-{k}", corpus._as16(disp), "uint16", ("voids",)))
    return out


def build() -> list[corpus.Case]:
    """The cases, all on the calibration half, damaged as the corpus damages its own."""
    cases = []
    for source, name, image, kind, classes in sources():
        for dmg in classes:
            rng = np.random.default_rng(corpus._seed(name, dmg))
            mask = corpus.damage(dmg, image, rng)
            cases.append(
                corpus.Case(f"{name}/{dmg}", source, "calibration", dmg, image, mask, kind)
            )
    return cases

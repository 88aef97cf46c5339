"""Synthetic tracking corpus with exact truth, in classes, split by sequence.

    python benchmarks/track_corpus.py            # prints the corpus' sequences and halves

`corpus(half)` returns {name: (frames, masks, class)} for half in ("calibration", "test").
Every class has SEQS sequences, made from seeds 0..SEQS-1; the even seeds form the
calibration half and the odd seeds the test half (deterministic: the same arrays every
run). Textures come from scikit-image's gravel, grass and brick photographs (crops at a
seed's offset) or from synthesised noise; nothing else is read.

Classes (frames of 72x96, float64 in [0, 1], 12-14 frames):

- ``textured``: one opaque textured blob over a strong ground texture, on a curved path at
  1.5-3 px a frame, shrinking and growing by up to 40%.
- ``two``: two textured, noisy ellipses with their own motions that drift together and
  merge, or start merged and split apart (a dividing blob), deforming.
- ``stopgo``: a textured object that speeds up, stops for three frames, then comes back at
  4.5 px a frame, over a strong texture.
- ``light``: a textured object under a shadow that sweeps across (even seeds' sequences of
  a pair) or a global flicker of brightness and contrast (odd), moving 1.5-2.5 px.
- ``distractor``: the object passes 2-3 px from a still look-alike of the same mean
  brightness and a different texture.
- ``flat``: a low-contrast object (a step of 0.1) with a flat interior under noise of
  standard deviation 0.06, deforming as it moves.
- ``slices``: consecutive slices of a deforming 3D blob (two lobes that join or part
  along z) with a 3D texture and noise.
"""

from __future__ import annotations

import numpy as np
from scipy import ndimage

CLASSES = ("textured", "two", "stopgo", "light", "distractor", "flat", "slices")
SEQS = 4  # sequences per class: seeds 0, 2 calibration; 1, 3 test
H, W = 72, 96


def _photo(rng, size):
    """A crop of one of scikit-image's texture photographs, zero mean, unit spread."""
    from skimage import data

    name = ("gravel", "grass", "brick")[int(rng.integers(3))]
    img = getattr(data, name)().astype(np.float64)
    y0, x0 = (int(rng.integers(0, 512 - s)) for s in size)
    crop = img[y0 : y0 + size[0], x0 : x0 + size[1]]
    return (crop - crop.mean()) / max(crop.std(), 1e-9)


def _noise(rng, size, scale):
    t = ndimage.gaussian_filter(rng.normal(size=size), scale, mode="wrap")
    return (t - t.mean()) / max(t.std(), 1e-9)


def _texture(rng, size, photo=None):
    """A ground or object texture: a photograph crop or smoothed noise (zero mean, unit
    standard deviation)."""
    if photo is None:
        photo = rng.random() < 0.5
    return _photo(rng, size) if photo else _noise(rng, size, rng.uniform(0.8, 2.0))


def _star(rng, k=3):
    """Random star shape: radius factor per angle, 1 + sum of a few harmonics."""
    amps = rng.uniform(0.0, 0.18, k)
    phases = rng.uniform(0, 2 * np.pi, k)
    return lambda th, t=0.0: (
        1
        + sum(
            a * np.cos((j + 2) * th + p + 0.15 * t * (j + 1))
            for j, (a, p) in enumerate(zip(amps, phases, strict=True))
        )
    )


def _shape(cy, cx, radius, star, t, sy=1.0, sx=1.0):
    y, x = np.mgrid[:H, :W] + 0.0
    dy, dx = (y - cy) / sy, (x - cx) / sx
    return np.hypot(dy, dx) < radius * star(np.arctan2(dy, dx), t)


def _compose(ground, layers, noise, rng):
    """ground with each (mask, object picture) pasted with a soft edge, plus noise."""
    img = ground.copy()
    for mask, obj in layers:
        alpha = ndimage.gaussian_filter(mask.astype(np.float64), 0.7)
        img = (1 - alpha) * img + alpha * obj
    return img + rng.normal(0, noise, img.shape)


def _sample(tex, cy, cx):
    """The object's texture carried with it: tex (2H x 2W) read at the object's frame."""
    return ndimage.shift(tex, (cy - H, cx - W), order=1, mode="wrap")[
        H // 2 : H // 2 + H, W // 2 : W // 2 + W
    ]


def _moving(
    rng, centres, scales, ground_std, obj_offset, obj_std, noise, star=None, radius=None, light=None
):
    """Frames and masks of one textured object along `centres` with `scales`."""
    star = star or _star(rng)
    radius = radius or rng.uniform(11, 14)
    ground = 0.5 + ground_std * _texture(rng, (H, W))
    otex = _texture(rng, (2 * H, 2 * W))
    frames, masks = [], []
    for t, ((cy, cx), s) in enumerate(zip(centres, scales, strict=True)):
        m = _shape(cy, cx, radius * s, star, t)
        obj = 0.5 + obj_offset + obj_std * _sample(otex, cy, cx)
        img = _compose(ground, [(m, obj)], noise, rng)
        if light is not None:
            img = light(img, t)
        frames.append(img)
        masks.append(m)
    return frames, masks


def _finish(frames, masks):
    return np.clip(np.array(frames), 0, 1), np.array(masks)


def seq_textured(seed):
    rng = np.random.default_rng(1000 + seed)
    n = 12
    speed = rng.uniform(1.5, 3.0)
    heading = rng.uniform(0, 2 * np.pi)
    turn = rng.uniform(-0.25, 0.25)
    cy, cx, centres = H / 2 - 4 * np.sin(heading), W / 2 - 10 * np.cos(heading), []
    for t in range(n):
        centres.append((cy, cx))
        a = heading + turn * t
        cy, cx = (
            np.clip(cy + speed * np.sin(a), 18, H - 18),
            np.clip(cx + speed * np.cos(a), 18, W - 18),
        )
    phase = rng.uniform(0, 2 * np.pi)
    scales = [1 + 0.2 * np.sin(0.6 * t + phase) for t in range(n)]
    offset = rng.choice([-1, 1]) * rng.uniform(0.12, 0.18)
    return _finish(*_moving(rng, centres, scales, 0.12, offset, 0.07, 0.04))


def seq_two(seed):
    rng = np.random.default_rng(2000 + seed)
    n = 12
    ground = 0.5 + 0.06 * _texture(rng, (H, W))
    merge = seed % 2 == 0 if seed < 2 else seed % 2 == 1  # both kinds in both halves
    texs = [_texture(rng, (2 * H, 2 * W), photo=False) for _ in range(2)]
    offs = [rng.uniform(0.18, 0.25) * rng.choice([-1, 1]) for _ in range(2)]
    stars = [_star(rng, 2), _star(rng, 2)]
    ang = rng.uniform(-0.5, 0.5)
    frames, masks = [], []
    for t in range(n):
        s = t / (n - 1)
        gap = 26 - 24 * s if merge else 2 + 24 * s  # centre distance beyond contact
        d = (20 + gap) / 2
        c = [
            (H / 2 - d * np.sin(ang) + 3 * s, W / 2 - d * np.cos(ang)),
            (H / 2 + d * np.sin(ang) - 3 * s, W / 2 + d * np.cos(ang)),
        ]
        layers, truth = [], np.zeros((H, W), bool)
        for k in range(2):
            m = _shape(*c[k], 10.5, stars[k], t, sy=1.0, sx=1.25 - 0.15 * s * (k + 1))
            obj = (
                0.5 + offs[k] * (1 if k == 0 else np.sign(offs[0])) + 0.08 * _sample(texs[k], *c[k])
            )
            layers.append((m, obj))
            truth |= m
        frames.append(_compose(ground, layers, 0.06, rng))
        masks.append(truth)
    return _finish(frames, masks)


def seq_stopgo(seed):
    rng = np.random.default_rng(3000 + seed)
    speeds = [1.5, 2.5, 3.5, 4.0, 0, 0, 0, -4.5, -4.5, -4.5, -4.5, -4.5, -4.5]
    heading = rng.uniform(-0.3, 0.3)
    cx, cy = 24.0, H / 2 + rng.uniform(-4, 4)
    centres = [(cy, cx)]
    for v in speeds:
        cx += v * np.cos(heading)
        cy += v * np.sin(heading)
        centres.append((cy, cx))
    scales = [1.0] * len(centres)
    offset = rng.choice([-1, 1]) * rng.uniform(0.12, 0.16)
    return _finish(
        *_moving(rng, centres, scales, 0.14, offset, 0.08, 0.04, radius=rng.uniform(10, 12))
    )


def seq_light(seed):
    rng = np.random.default_rng(4000 + seed)
    n = 12
    speed = rng.uniform(1.5, 2.5)
    cy, cx = H / 2 + rng.uniform(-5, 5), 26.0
    centres = [(cy + 0.3 * speed * t, cx + speed * t) for t in range(n)]
    gains = rng.uniform(0.6, 1.3, n)
    offsets = rng.uniform(-0.15, 0.15, n)
    y, x = np.mgrid[:H, :W] + 0.0

    def shadow(img, t):
        front = 4 + 8.0 * t
        return img * (1 - 0.55 / (1 + np.exp((x + 0.3 * y - front) / 3.0)))

    def flicker(img, t):
        return gains[t] * (img - 0.5) + 0.5 + offsets[t]

    light = shadow if (seed // 2) % 2 == 0 else flicker
    offset = rng.choice([-1, 1]) * rng.uniform(0.12, 0.16)
    return _finish(*_moving(rng, centres, [1.0] * n, 0.1, offset, 0.08, 0.04, light=light))


def seq_distractor(seed):
    rng = np.random.default_rng(5000 + seed)
    n = 12
    star = _star(rng)
    radius = rng.uniform(10, 12)
    offset = rng.choice([-1, 1]) * rng.uniform(0.12, 0.16)
    ground = 0.5 + 0.08 * _texture(rng, (H, W))
    otex = _noise(rng, (2 * H, 2 * W), 0.9)
    dtex = _noise(rng, (H, W), 3.0)
    gap = rng.uniform(2, 3)
    dy = 2 * radius + gap
    side = rng.choice([-1, 1])
    dist = _shape(H / 2 + side * dy / 2, W / 2, radius, _star(rng), 0)
    speed = rng.uniform(2.0, 3.0)
    frames, masks = [], []
    for t in range(n):
        cy, cx = H / 2 - side * dy / 2, 20 + speed * t
        m = _shape(cy, cx, radius, star, t)
        obj = 0.5 + offset + 0.08 * _sample(otex, cy, cx)
        img = _compose(ground, [(dist, 0.5 + offset + 0.08 * dtex), (m, obj)], 0.04, rng)
        frames.append(img)
        masks.append(m)
    return _finish(frames, masks)


def seq_flat(seed):
    rng = np.random.default_rng(6000 + seed)
    n = 12
    star = _star(rng)
    radius = rng.uniform(12, 15)
    ground = 0.5 + 0.02 * _noise(rng, (H, W), 4.0)
    sign = rng.choice([-1, 1])
    speed, heading = rng.uniform(1.0, 2.0), rng.uniform(-0.5, 0.5)
    frames, masks = [], []
    for t in range(n):
        cy, cx = H / 2 + speed * t * np.sin(heading), 30 + speed * t * np.cos(heading)
        m = _shape(cy, cx, radius * (1 + 0.1 * np.sin(0.5 * t)), star, 2 * t)
        frames.append(_compose(ground, [(m, 0.5 + sign * 0.1)], 0.06, rng))
        masks.append(m)
    return _finish(frames, masks)


def seq_slices(seed):
    rng = np.random.default_rng(7000 + seed)
    n = 12
    z, y, x = np.mgrid[: n * 2, :H, :W] + 0.0
    # Two lobes whose centres drift with z: they join (or part) along the stack.
    join = seed % 2 == 0
    field = np.full(z.shape, -np.inf)
    for k, s in enumerate((-1, 1)):
        d = (26 - 22 * z / (2 * n)) if join else (4 + 22 * z / (2 * n))
        cy = H / 2 + rng.uniform(-4, 4) + 4 * np.sin(z / 7 + k)
        cx = W / 2 + s * d / 2 * 1.5
        r = rng.uniform(11, 14) * (1 + 0.15 * np.sin(z / 5 + 2 * k))
        field = np.maximum(field, 1 - np.hypot(y - cy, x - cx) / r)
    bump = ndimage.gaussian_filter(rng.normal(size=field.shape), 3)
    vol = field + 0.15 * bump / np.abs(bump).max() > 0.0
    tex = ndimage.gaussian_filter(rng.normal(size=vol.shape), 1.2)
    tex /= tex.std()
    sign = rng.choice([-1, 1])
    img = 0.5 + sign * 0.15 * ndimage.gaussian_filter(vol * 1.0, 0.8) + 0.05 * tex
    img += rng.normal(0, 0.05, img.shape)
    return np.clip(img[::2], 0, 1), vol[::2]


MAKERS = {
    "textured": seq_textured,
    "two": seq_two,
    "stopgo": seq_stopgo,
    "light": seq_light,
    "distractor": seq_distractor,
    "flat": seq_flat,
    "slices": seq_slices,
}


def half_of(seed: int) -> str:
    return "calibration" if seed % 2 == 0 else "test"


def corpus(half: str | None = None, classes=CLASSES, seqs: int = SEQS):
    """{name: (frames, masks, class)} of one half ('calibration', 'test') or both (None)."""
    out = {}
    for cls in classes:
        for seed in range(seqs):
            if half is not None and half_of(seed) != half:
                continue
            frames, masks = MAKERS[cls](seed)
            out[f"{cls}-{seed}"] = (frames, masks, cls)
    return out


def main():
    from scipy.ndimage import label

    for name, (frames, masks, _cls) in corpus().items():
        ious = [(m & masks[0]).sum() / (m | masks[0]).sum() for m in masks]
        pieces = [label(m)[1] for m in masks]
        print(
            f"{name:14s} {half_of(int(name.split('-')[1])):12s} {frames.shape} "
            f"area {masks.sum((1, 2)).min()}-{masks.sum((1, 2)).max()} "
            f"IoU with frame 0 down to {min(ious):.2f}, pieces {min(pieces)}-{max(pieces)}"
        )


if __name__ == "__main__":
    main()

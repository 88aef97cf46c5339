"""Benchmark cases for texture inpainting, shared with benchmarks/inpaint_quality.py.

    from inpaint_texture_cases import texture_cases, edge_energy

texture_cases() returns a list of dicts {name, class, image, mask}:

- class 'texture': scikit-image's brick, grass and gravel, and textured crops of its photos
  (the cat's fur, a tissue stain, the astronaut's suit and flag), 256 x 256, with three
  holes of 15-40 px (discs and squares) each;
- class 'periodic': synthetic periodic patterns (a grating, a checkerboard of two colours,
  a lattice of dots, tiles) with 20-40 px holes;
- class 'thick': one hole of 50-100 px in a photo.

Images are uint8 (greyscale (rows, cols) or colour (rows, cols, 3)) or float in [0, 1];
masks are bool, True where the image is to be filled. The holes are placed by fixed seeds.

edge_energy(result, original, mask) is the texture's energy kept in the hole: the mean
gradient magnitude of the result in the hole's interior over the original's (1 for the
texture's own energy, near 0 for a smooth fill).
"""

from __future__ import annotations

import numpy as np
from scipy import ndimage


def _holes(shape, sizes, seed, shapes=("disc", "square")):
    rng = np.random.default_rng(seed)
    ny, nx = shape
    mask = np.zeros(shape, bool)
    y, x = np.mgrid[0:ny, 0:nx]
    for k, size in enumerate(sizes):
        for _ in range(100):  # place each hole apart from the others
            cy = rng.integers(size // 2 + 4, ny - size // 2 - 4)
            cx = rng.integers(size // 2 + 4, nx - size // 2 - 4)
            kind = shapes[k % len(shapes)]
            if kind == "disc":
                hole = (y - cy) ** 2 + (x - cx) ** 2 <= (size / 2) ** 2
            else:
                h = size // 2
                hole = (abs(y - cy) <= h) & (abs(x - cx) <= h)
            if not (ndimage.binary_dilation(hole, iterations=8) & mask).any():
                break
        mask |= hole
    return mask


def _periodic_patterns(n=192):
    y, x = np.mgrid[0:n, 0:n].astype(np.float64)
    grating = 0.5 + 0.4 * np.sin(2 * np.pi * (x / 16 + y / 24))
    checker = ((x // 12 + y // 12) % 2)[..., None] * np.array([0.8, 0.2, 0.3]) + (
        1 - (x // 12 + y // 12) % 2
    )[..., None] * np.array([0.1, 0.5, 0.9])
    dots = 0.15 + 0.7 * (((x % 14) - 7) ** 2 + ((y % 14) - 7) ** 2 < 16)
    tiles = np.stack(
        [
            0.5 + 0.35 * np.sin(2 * np.pi * x / 20) * np.cos(2 * np.pi * y / 20),
            0.5 + 0.35 * np.cos(2 * np.pi * (x + y) / 20),
            0.3 + 0.4 * ((x % 20 < 4) | (y % 20 < 4)),
        ],
        -1,
    )
    return {"grating": grating, "checker": checker, "dots": dots, "tiles": tiles}


def texture_cases() -> list[dict]:
    from skimage import data

    cases = []
    textures = {
        "brick": data.brick()[128:384, 128:384],
        "grass": data.grass()[128:384, 128:384],
        "gravel": data.gravel()[128:384, 128:384],
        "fur": data.chelsea()[30:286, 150:406],
        "tissue": data.immunohistochemistry()[200:456, 200:456],
        "suit": data.astronaut()[256:512, 0:256],
    }
    for i, (name, image) in enumerate(textures.items()):
        mask = _holes(image.shape[:2], (16, 28, 40), seed=10 + i)
        cases.append({"name": name, "class": "texture", "image": image, "mask": mask})
    for i, (name, image) in enumerate(_periodic_patterns().items()):
        mask = _holes(image.shape[:2], (20, 30, 40), seed=20 + i)
        cases.append({"name": name, "class": "periodic", "image": image, "mask": mask})
    photos = [
        ("astronaut", data.astronaut(), (330, 120), 80, "square"),
        ("coffee", data.coffee(), (100, 300), 100, "square"),
        ("chelsea", data.chelsea(), (200, 300), 70, "disc"),
        ("camera", data.camera(), (380, 300), 60, "disc"),
        ("rocket", data.rocket(), (320, 480), 90, "square"),
    ]
    for name, image, (cy, cx), size, kind in photos:
        ny, nx = image.shape[:2]
        y, x = np.mgrid[0:ny, 0:nx]
        if kind == "disc":
            mask = (y - cy) ** 2 + (x - cx) ** 2 <= (size / 2) ** 2
        else:
            mask = (abs(y - cy) < size // 2) & (abs(x - cx) < size // 2)
        cases.append({"name": f"{name}-{size}", "class": "thick", "image": image, "mask": mask})
    return cases


def _as_float(image) -> np.ndarray:
    image = np.asarray(image)
    if np.issubdtype(image.dtype, np.integer):
        return image.astype(np.float64) / np.iinfo(image.dtype).max
    return image.astype(np.float64)


def _gradient_magnitude(image) -> np.ndarray:
    f = _as_float(image)
    if f.ndim == 2:
        f = f[..., None]
    gy, gx = np.gradient(f, axis=(0, 1))
    return np.sqrt(gx**2 + gy**2).mean(axis=-1)


def edge_energy(result, original, mask) -> float:
    """Mean gradient magnitude of ``result`` in the hole's interior over ``original``'s.

    The interior is the mask eroded by 2 pixels, so that no central difference reaches a
    known pixel and the seam itself is not counted.
    """
    mask = np.asarray(mask, bool)
    inner = ndimage.binary_erosion(mask, iterations=2)
    if not inner.any():
        inner = mask
    ref = _gradient_magnitude(original)[inner].mean()
    return float(_gradient_magnitude(result)[inner].mean() / max(ref, 1e-12))

"""Test images and scenes for trying clpde, like ``skimage.data``.

Each function builds its data from scikit-image's bundled photos or from formulas, so
nothing is downloaded:

- inpainting: `damaged_astronaut` (a photo with text and scratches painted over it) and
  `damage_mask` (such damage for any image size);
- region tracking: `region_scene` (thesis Figure 2.7's toy cases and caps on a sphere).

The surfaces' sample shapes and the data the chapter-4 figures put on them are in
clpde.surface (`surface_shape`, `checker`, `colour_pattern`, `surface_noise`): they are
ImplicitSurfaces, and this module, on the ground floor, imports no capability.

The command line's demonstrations (`clpde inpaint --demo`, `clpde regions`) and the examples
take their data from here.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .errors import InputError

__all__ = [
    "REGION_SCENES",
    "RegionScene",
    "damage_mask",
    "damaged_astronaut",
    "region_scene",
]


# ---- inpainting -------------------------------------------------------------------------


def damage_mask(
    shape: tuple[int, int], seed: int = 3, text: bool = True, scratches: bool = True
) -> np.ndarray:
    """Text and thin scratches over an image, as a boolean mask.

    Parameters
    ----------
    shape : (rows, columns)
        The image's size.
    seed : int
        Seed of the scratches' random placement.
    text, scratches : bool
        Whether to draw four lines of text (a caption and a date) and six gently curved
        scratches, 1 or 2 pixels wide.

    Returns
    -------
    mask : (rows, columns) bool ndarray
        True on the damage (about 8% of the pixels with both kinds).

    Examples
    --------
    >>> from clpde.data import damage_mask
    >>> mask = damage_mask((128, 128))
    >>> mask.shape, mask.dtype
    ((128, 128), dtype('bool'))
    >>> bool(0.02 < mask.mean() < 0.2)
    True
    """
    from PIL import Image, ImageDraw, ImageFont

    ny, nx = shape
    canvas = Image.new("L", (nx, ny), 0)
    draw = ImageDraw.Draw(canvas)
    size = max(12, nx // 13)
    font = ImageFont.load_default(size=size)
    lines = ["Summer 1984", "Houston, TX", "do not copy", "25.12.1984"]
    for k, line in enumerate(lines if text else []):
        draw.text(
            (nx // 20 + (k % 2) * nx // 6, ny // 10 + k * ny // 4.4),
            line,
            fill=255,
            font=font,
            stroke_width=max(1, size // 16),
            stroke_fill=255,
        )
    rng = np.random.default_rng(seed)
    for _ in range(6 if scratches else 0):  # scratches: gently curved, 1-2 pixels wide
        x0, y0 = rng.uniform(0, nx), rng.uniform(0, ny)
        angle = rng.uniform(0, np.pi)
        t = np.linspace(-0.35, 0.35, 30) * nx
        bend = rng.uniform(-0.2, 0.2) * t**2 / nx
        xs = x0 + t * np.cos(angle) - bend * np.sin(angle)
        ys = y0 + t * np.sin(angle) + bend * np.cos(angle)
        draw.line(list(zip(xs, ys, strict=False)), fill=255, width=int(rng.integers(1, 3)))
    return np.asarray(canvas) > 0


def damaged_astronaut() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """scikit-image's astronaut photo with a caption, a date and scratches painted white.

    Returns
    -------
    original : (512, 512, 3) uint8 ndarray
        The photo.
    damaged : (512, 512, 3) uint8 ndarray
        The same with the damage in white.
    mask : (512, 512) bool ndarray
        Where the damage is (`damage_mask` of the photo's size): what inpainting fills.

    Examples
    --------
    >>> from clpde.data import damaged_astronaut
    >>> original, damaged, mask = damaged_astronaut()
    >>> original.shape, damaged.dtype, mask.dtype
    ((512, 512, 3), dtype('uint8'), dtype('bool'))
    >>> bool((damaged[mask] == 255).all() and (damaged[~mask] == original[~mask]).all())
    True
    """
    from skimage import data

    original = data.astronaut()
    mask = damage_mask(original.shape[:2])
    damaged = original.copy()
    damaged[mask] = 255
    return original, damaged, mask


# ---- region tracking --------------------------------------------------------------------

REGION_SCENES = ("split", "merge", "cap-expand", "cap-translate")


@dataclass
class RegionScene:
    """The inputs of one `clpde.track_region` run: ``track_region(phi, region,
    spacing=spacing, origin=origin, **options)``."""

    phi: np.ndarray
    region: object
    spacing: float
    origin: tuple
    options: dict


def _axes(h, extent):
    """Grid coordinates covering [-e, e] per axis (x, y, z), broadcastable."""
    axes = [np.arange(-e, e + 0.5 * h, h) for e in extent]
    return (
        axes[0][None, None, :],
        axes[1][None, :, None],
        axes[2][:, None, None],
        tuple(a[0] for a in axes),
    )


def _capsule(x, y, z, half, r):
    return np.sqrt((x - np.clip(x, -half, half)) ** 2 + y**2 + z**2) - r


def _two_spheres(x, y, z, c, r):
    return np.minimum(np.sqrt((x - c) ** 2 + y**2 + z**2), np.sqrt((x + c) ** 2 + y**2 + z**2)) - r


def region_scene(name: str, spacing: float = 0.05) -> RegionScene:
    """Thesis Figure 2.7's toy cases and two checks on a sphere, for `clpde.track_region`.

    Parameters
    ----------
    name : {'split', 'merge', 'cap-expand', 'cap-translate'}
        'split': a capsule morphs into two spheres and a belt around its middle splits in
        two; 'merge': two spheres morph into a capsule and their facing caps join;
        'cap-expand': a cap of angular radius 60 degrees on a fixed sphere grows (beta=0.5);
        'cap-translate': the same cap on a sphere carried by a constant velocity.
    spacing : float
        The grid's spacing (the shapes are about 1 across).

    Returns
    -------
    RegionScene
        phi (the surface's level set on the grid), region (the region's level set), the
        spacing, the grid's origin and the options of the run (beta, target, velocity, t).

    Examples
    --------
    >>> from clpde.data import region_scene
    >>> scene = region_scene("split", spacing=0.1)
    >>> scene.phi.shape, scene.options["beta"], scene.options["t"]
    ((31, 31, 46), 'morph', 4.0)
    """
    h = float(spacing)
    margin = 10 * h  # the band plus its reinitialisation ring
    if name in ("split", "merge"):
        x, y, z, origin = _axes(h, (1.25 + margin, 0.5 + margin, 0.5 + margin))
        shape = (z.size, y.size, x.size)
        if name == "split":
            start, target = _capsule(x, y, z, 0.6, 0.45), _two_spheres(x, y, z, 0.75, 0.45)
            region = np.sqrt(x**2 + y**2) - 0.8 + 0 * z  # a belt around the capsule's middle
        else:
            start, target = _two_spheres(x, y, z, 0.55, 0.45), _capsule(x, y, z, 0.6, 0.45)
            region = np.abs(x) - 0.35 + 0 * y + 0 * z  # the spheres' facing caps

        def b(a):
            return np.ascontiguousarray(np.broadcast_to(a, shape))

        return RegionScene(
            b(start), b(region), h, origin, {"beta": "morph", "target": b(target), "t": 4.0}
        )
    if name in ("cap-expand", "cap-translate"):
        shift = np.array([-0.25, 0.0, -0.1]) if name == "cap-translate" else np.zeros(3)
        x, y, z, origin = _axes(h, (1.4 + margin,) * 3)
        phi = np.sqrt((x - shift[0]) ** 2 + (y - shift[1]) ** 2 + (z - shift[2]) ** 2) - 0.9
        region = np.broadcast_to(0.45 + shift[2] - z, phi.shape)  # cap of angular radius 60 deg
        options = (
            {"beta": 0.5, "t": 0.5}
            if name == "cap-expand"
            else {"velocity": (0.5, 0.0, 0.2), "t": 1.0}
        )
        return RegionScene(phi, np.ascontiguousarray(region), h, origin, options)
    raise InputError(f"scene must be one of {', '.join(REGION_SCENES)}, not {name!r}")

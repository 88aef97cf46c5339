"""Synthetic inpainting cases: structure (stripes, an edge, rings, a curved edge, a
T-junction) crossing a slot or hole, as (uint8 image, mask). The tests
(tests/inpainting/test_inpaint_methods.py) and the benchmarks (inpaint_quality.py,
inpaint_pictures.py) share them."""

from __future__ import annotations

import numpy as np


def _u8(image):
    return np.round(np.clip(image, 0, 1) * 255).astype(np.uint8)


def stripes_case(angle_deg, size=128, period=16, slot=6):
    """Sharp stripes (anti-aliased edges) crossing a vertical slot `slot` px wide; the
    isophotes make `angle_deg` with the slot's normal (0: straight across)."""
    y, x = np.mgrid[0:size, 0:size].astype(float)
    a = np.deg2rad(angle_deg)
    t = -(x - size / 2) * np.sin(a) + (y - size / 2) * np.cos(a)
    image = 0.15 + 0.7 * np.clip(0.5 + 2.0 * np.sin(2 * np.pi * t / period), 0, 1)
    mask = np.zeros((size, size), bool)
    mask[:, size // 2 - slot // 2 : size // 2 - slot // 2 + slot] = True
    return _u8(image), mask


def edge_case(angle_deg, size=128, slot=6, width=1.0):
    """One straight soft edge crossing the slot at `angle_deg`."""
    y, x = np.mgrid[0:size, 0:size].astype(float)
    a = np.deg2rad(angle_deg)
    t = -(x - size / 2) * np.sin(a) + (y - size / 2) * np.cos(a)
    mask = np.zeros((size, size), bool)
    mask[:, size // 2 - slot // 2 : size // 2 - slot // 2 + slot] = True
    return _u8(0.2 + 0.6 / (1 + np.exp(-t / width))), mask


def rings_case(size=128, period=14, slot=6):
    """Concentric sharp rings crossing a thin horizontal slot through their centre's row
    (offset so the slot meets the rings at every angle)."""
    y, x = np.mgrid[0:size, 0:size].astype(float)
    r = np.hypot(y - size * 0.62, x - size / 2)
    image = 0.15 + 0.7 * np.clip(0.5 + 2.0 * np.sin(2 * np.pi * r / period), 0, 1)
    mask = np.zeros((size, size), bool)
    mask[size // 2 - slot // 2 : size // 2 - slot // 2 + slot, :] = True
    return _u8(image), mask


def curved_edge_case(size=128, slot=8):
    """The soft edge of a large disc, crossed by a vertical slot where it curves."""
    y, x = np.mgrid[0:size, 0:size].astype(float)
    r = np.hypot(y - size * 1.1, x - size / 2)
    image = 0.2 + 0.6 / (1 + np.exp(-(r - size * 0.75) / 1.2))
    mask = np.zeros((size, size), bool)
    mask[:, size // 2 + 10 : size // 2 + 10 + slot] = True
    return _u8(image), mask


def t_junction_case(size=128, hole=14):
    """A dark horizontal bar meeting a vertical one, the junction under a square hole."""
    y, x = np.mgrid[0:size, 0:size].astype(float)
    bar_h = np.abs(y - size / 2) <= 5
    bar_v = (np.abs(x - size / 2) <= 5) & (y >= size / 2)
    image = np.where(bar_h | bar_v, 0.15, 0.85)
    from scipy import ndimage

    image = ndimage.gaussian_filter(image, 0.7)
    mask = np.zeros((size, size), bool)
    c = size // 2
    mask[c - hole // 2 : c + hole - hole // 2, c - hole // 2 : c + hole - hole // 2] = True
    return _u8(image), mask

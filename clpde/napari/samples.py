"""Sample data for the plugin: the damaged astronaut, a short tracking sequence, a mesh."""

from __future__ import annotations

from typing import Any

import numpy as np

import clpde

LayerData = list[tuple[Any, dict, str]]


def damaged_astronaut() -> LayerData:
    """scikit-image's astronaut with painted damage, and the damage as a Labels layer.

    Returns
    -------
    list of layer data tuples
        The damaged photo (image) and its mask (labels, 1 where to fill).
    """
    _, damaged, mask = clpde.data.damaged_astronaut()
    return [
        (damaged, {"name": "damaged astronaut", "rgb": True}, "image"),
        (mask.astype(np.uint8), {"name": "damage", "opacity": 0.6}, "labels"),
    ]


def tracking_sequence(frames: int = 16, size: int = 96, seed: int = 0) -> LayerData:
    """A textured blob that drifts and deforms over textured ground, with its first-frame
    label (draw on any frame, then track).

    Returns
    -------
    list of layer data tuples
        The frames (image, (T, H, W) float32) and labels with the first frame's object.
    """
    rng = np.random.default_rng(seed)
    y, x = np.mgrid[:size, :size].astype(np.float32)
    ground = rng.normal(0.3, 0.08, (size, size)).astype(np.float32)
    stack = np.empty((frames, size, size), np.float32)
    labels = np.zeros((frames, size, size), np.int32)
    for t in range(frames):
        cy, cx = size * 0.5 + 6 * np.sin(t / 5), size * 0.3 + 2.0 * t
        ry, rx = size * 0.16 * (1 + 0.2 * np.sin(t / 3)), size * 0.2
        inside = ((y - cy) / ry) ** 2 + ((x - cx) / rx) ** 2 < 1
        stack[t] = np.where(inside, 0.75, ground) + rng.normal(0, 0.03, (size, size))
        if t == 0:
            labels[0][inside] = 1
    return [
        (stack, {"name": "tracking sequence"}, "image"),
        (labels, {"name": "objects"}, "labels"),
    ]


def torus() -> LayerData:
    """trimesh's torus as a Surface layer, its values a noisy height (for the flows).

    Returns
    -------
    list of one layer data tuple
        (vertices, faces, values) of a torus.
    """
    import trimesh

    mesh = trimesh.creation.torus(
        major_radius=1.0, minor_radius=0.4, major_sections=64, minor_sections=32
    )
    rng = np.random.default_rng(0)
    values = mesh.vertices[:, 2] + 0.15 * rng.standard_normal(len(mesh.vertices))
    # napari orders coordinates (z, y, x): reversed, with the faces' winding reversed too so
    # that normals still point out, napari's default 3-D view looks down the torus's axis
    vertices = np.asarray(mesh.vertices[:, ::-1], np.float32)
    faces = np.asarray(mesh.faces[:, ::-1], np.int32)
    return [((vertices, faces, values), {"name": "torus", "colormap": "viridis"}, "surface")]

"""What region tracking gives back at each saved time: the surface's mesh split and coloured
by region (RegionFrame, made by make_frame from a tracker's level sets)."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import trimesh
from numpy.typing import ArrayLike
from scipy.ndimage import map_coordinates

from .._progress import State
from ..errors import InputError
from .mesh import region_colours, split_regions, surface_mesh


@dataclass
class RegionFrame(State):
    """The surface and its regions at one saved time."""

    time: float
    mesh: object  # trimesh.Trimesh with per-vertex region colours
    face_labels: np.ndarray  # region index of each face, -1 outside every region
    boundaries: list = field(default_factory=list)  # (k, 3) points on each region's boundary
    phi: np.ndarray | None = None  # world-unit level sets, (nz, ny, nx)
    phihat: np.ndarray | None = None  # (regions, nz, ny, nx)
    step: int = 0  # the tracker's steps so far

    def area(self, label: int | None = None) -> float:
        """Area of region `label` (of the whole surface when None)."""
        areas = self.mesh.area_faces
        return float(areas.sum() if label is None else areas[self.face_labels == label].sum())

    def area_fraction(self, label: int = 0) -> float:
        return self.area(label) / self.area()


def make_frame(
    tracker,
    time: float,
    origin: ArrayLike,
    keep_volumes: bool = False,
    palette: ArrayLike | None = None,
    partition: bool = False,
) -> RegionFrame:
    """The mesh of Phi = 0 split along each Phi-hat = 0, coloured by region (with partition,
    every face in one: slivers where the labels' boundaries part by rounding go to the
    nearest region)."""
    phi, phihat = tracker.volumes()
    h = tracker.h
    if not (phi.min() < 0 < phi.max()):  # gone between two band rebuilds
        raise InputError(
            f"the surface vanished by t = {time:g} (Phi has no zero level set "
            "left on the grid); track for a shorter time"
        )
    mesh = surface_mesh(phi, h, origin)
    idx = ((np.asarray(mesh.vertices) - origin) / h)[:, ::-1].T  # (z, y, x) index coordinates
    vals = np.stack([map_coordinates(p, idx, order=1, mode="nearest") for p in phihat], axis=1)
    verts, faces, labels, boundaries = split_regions(mesh.vertices, vals, mesh.faces, partition)
    vertex_label = np.full(len(verts), -1)
    vertex_label[faces.reshape(-1)] = np.repeat(labels, 3)
    rgb = region_colours(vertex_label, palette)
    colours = np.concatenate(
        [np.rint(255 * rgb).astype(np.uint8), np.full((len(rgb), 1), 255, np.uint8)], 1
    )
    out = trimesh.Trimesh(verts, faces, vertex_colors=colours, process=False)
    return RegionFrame(
        time,
        out,
        labels,
        boundaries,
        phi if keep_volumes else None,
        phihat if keep_volumes else None,
        tracker.steps,
    )

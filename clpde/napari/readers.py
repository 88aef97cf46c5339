"""napari readers: films (MP4, MKV, AVI, MOV) into a 2-D + t image layer, meshes (through
trimesh) into a Surface layer."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from clpde.io.video import VideoReader

FILM_SUFFIXES = (".mp4", ".mkv", ".avi", ".mov", ".m4v", ".webm")
MESH_SUFFIXES = (".ply", ".obj", ".stl", ".off", ".glb", ".gltf")

LayerData = list[tuple[Any, dict, str]]


def _one_path(path: str | list[str]) -> str | None:
    if isinstance(path, list):
        return path[0] if len(path) == 1 else None
    return path


def get_film_reader(path: str | list[str]) -> Callable[[str], LayerData] | None:
    """npe2 reader hook: a function that reads the film at `path`, or None for other files.

    Parameters
    ----------
    path : str or list of str
        What the user opened; one film file.

    Returns
    -------
    callable or None
        `read_film`, when `path` is a film.
    """
    one = _one_path(path)
    if one is None or Path(one).suffix.lower() not in FILM_SUFFIXES:
        return None
    return read_film


def read_film(path: str | list[str]) -> LayerData:
    """A film's frames as one image layer of shape (T, H, W, 3), with the film's path and
    frame rate in the layer's metadata (the film widget writes the film back from them).

    Parameters
    ----------
    path : str or list of str
        The film file.

    Returns
    -------
    list of (data, attributes, "image")
    """
    one = _one_path(path)
    reader = VideoReader(one)
    frames = np.stack(list(reader))
    meta = {"clpde_film": str(one), "frame_rate": float(reader.info.rate)}
    return [(frames, {"name": Path(one).stem, "rgb": frames.ndim == 4, "metadata": meta}, "image")]


def get_mesh_reader(path: str | list[str]) -> Callable[[str], LayerData] | None:
    """npe2 reader hook: a function that reads the mesh at `path`, or None for other files.

    Parameters
    ----------
    path : str or list of str
        What the user opened; one mesh file.

    Returns
    -------
    callable or None
        `read_mesh`, when `path` is a mesh.
    """
    one = _one_path(path)
    if one is None or Path(one).suffix.lower() not in MESH_SUFFIXES:
        return None
    return read_mesh


def read_mesh(path: str | list[str]) -> LayerData:
    """A mesh as a Surface layer (vertices, faces, values), through trimesh. Values are the
    mesh's vertex scalars when it has some (PLY ``quality`` or ``value``), else its height.

    Parameters
    ----------
    path : str or list of str
        The mesh file.

    Returns
    -------
    list of ((vertices, faces, values), attributes, "surface")
    """
    import trimesh

    one = _one_path(path)
    mesh = trimesh.load(one, force="mesh", process=False)
    attrs = getattr(mesh, "vertex_attributes", {}) or {}
    values = next(
        (np.asarray(attrs[k], np.float64) for k in ("value", "quality") if k in attrs), None
    )
    if values is None or values.shape != (len(mesh.vertices),):
        values = np.asarray(mesh.vertices[:, 2], np.float64)
    data = (np.asarray(mesh.vertices, np.float32), np.asarray(mesh.faces, np.int32), values)
    return [(data, {"name": Path(one).stem, "colormap": "viridis"}, "surface")]

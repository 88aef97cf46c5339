"""`clpde surface inpaint`'s files: reading a mesh's MASK and VALUES files, and writing the
before/after pictures and the filled meshes. The fill itself is in inpainting.py; this
module stands apart because it draws (render.py) and writes (runs.py), which the library's
fill needs neither of."""

from __future__ import annotations

import os

import numpy as np

from ..errors import InputError
from ..io.images import check_not_overwriting_input, check_output_folder, output_folder
from .inpainting import MISSING_COLOUR, inpaint, mesh_values, vertex_mask
from .mesh_sdf import load_mesh
from .render import (
    colormap,
    export_mesh,
    render_mesh,
    view_rotation,
    with_colour_bar,
    with_title,
)
from .runs import write_png


def read_vertex_file(path, what: str, dtype=None) -> np.ndarray:
    """A .npy array, or whitespace-separated numbers in a text file (.txt, .csv, ...)."""
    path = os.fspath(path)
    if not os.path.isfile(path):
        raise InputError(f"{what} file {path} does not exist")
    try:
        if path.lower().endswith(".npy"):
            return np.load(path, allow_pickle=False)
        return np.loadtxt(
            path, dtype=dtype, ndmin=1, delimiter="," if path.endswith(".csv") else None
        )
    except (ValueError, OSError) as exc:
        raise InputError(f"cannot read {what} file {path}: {exc}") from None


def read_missing(path, vertices: int) -> np.ndarray:
    """The per-vertex mask of a MASK file: a .npy of booleans (one per vertex) or of
    integer vertex indices, or a text file of vertex indices."""
    data = read_vertex_file(path, "mask", dtype=np.int64)
    if np.issubdtype(data.dtype, np.floating) and np.all(data == np.round(data)):
        data = data.astype(np.int64)
    return vertex_mask(data.reshape(-1) if data.ndim else data[None], vertices)


def _facing(direction: np.ndarray) -> tuple[float, float]:
    """(azimuth, elevation) of the view that looks at the surface from `direction`."""
    best, view = -2.0, (30.0, 20.0)
    for a in range(0, 360, 10):
        for e in range(-80, 81, 10):
            d = float(view_rotation(a, e)[2] @ direction)
            if d > best:
                best, view = d, (float(a), float(e))
    return view


def coloured(mesh, data: np.ndarray, mask: np.ndarray | None, lo=None, hi=None):
    """A copy of mesh coloured by vertex data (RGB in 0..255 or 0..1, or a scalar through
    the colour ramp), the masked vertices grey."""
    out = mesh.copy()
    if data.ndim == 1:
        rgb = colormap(data, lo, hi)
        out.vertex_attributes["u"] = data.astype(np.float64)
    else:
        rgb = data[:, :3].astype(np.float64)
        rgb = rgb / 255.0 if np.issubdtype(data.dtype, np.integer) or rgb.max() > 1 else rgb
    if mask is not None:
        rgb[mask] = MISSING_COLOUR
    alpha = np.full((len(rgb), 1), 255, np.uint8)
    out.visual.vertex_colors = np.concatenate(
        [np.rint(255 * np.clip(rgb, 0, 1)).astype(np.uint8), alpha], 1
    )
    return out


def inpaint_file(
    mesh,
    output,
    *,
    missing,
    values=None,
    method: str = "harmonic",
    resolution: int = 128,
    size: int = 400,
    overwrite: bool = False,
    device=None,
    progress=None,
) -> list[str]:
    """`clpde surface inpaint`: fill the vertices of `mesh` (a file) that the MASK file
    `missing` names, from its vertex colours or the VALUES file `values`; writes
    before.png, after.png (the hole grey before), result.ply and result.glb (the filled
    colours, and a scalar as the vertex property 'u') into the folder `output`. Returns
    report lines."""
    inputs = [mesh, missing] + ([values] if values is not None else [])
    check_not_overwriting_input(inputs, output)
    check_output_folder(output, overwrite, option="--overwrite")
    if resolution < 16:
        raise InputError(f"--resolution must be at least 16, not {resolution}")
    if size < 16:
        raise InputError(f"--size must be at least 16, not {size}")
    if not os.path.isfile(os.fspath(mesh)):
        raise InputError(f"mesh file {mesh} does not exist (inpaint needs a mesh file)")
    loaded = load_mesh(mesh)
    mask = read_missing(missing, len(loaded.vertices))
    data = mesh_values(loaded, None if values is None else read_vertex_file(values, "values"))
    if data.ndim == 2 and data.shape[1] not in (1, 3):
        raise InputError(f"values have {data.shape[1]} channels; give a scalar or RGB per vertex")
    data = data[:, 0] if data.ndim == 2 and data.shape[1] == 1 else data
    filled, info = inpaint(
        loaded,
        data,
        mask,
        method=method,
        resolution=resolution,
        device=device,
        progress=progress,
        return_info=True,
    )
    verts = np.asarray(loaded.vertices, np.float64)
    direction = verts[mask].mean(axis=0) - verts.mean(axis=0) if mask.any() else np.ones(3)
    direction = direction / max(np.linalg.norm(direction), 1e-30)
    # seen from above the hole's side when that side faces sideways (a torus seen edge-on
    # shows little of it)
    direction = direction + np.array([0.0, 0.0, 0.85]) * (1 - abs(direction[2]))
    a, e = _facing(direction / np.linalg.norm(direction))
    views = ((a - 35.0, e), (a + 35.0, e))
    scalar = data.ndim == 1
    lo = hi = None
    if scalar:
        lo, hi = float(filled.min()), float(filled.max())
    pictures = {
        "before": (
            coloured(loaded, data, mask, lo, hi),
            f"before: {int(mask.sum())} of {len(mask)} vertices missing (grey)",
        ),
        "after": (
            coloured(loaded, filled, None, lo, hi),
            f"after: {method} fill on the implicit surface ({info.iterations} steps)",
        ),
    }
    with output_folder(output, overwrite) as staging:
        for name, (m, title) in pictures.items():
            image = np.concatenate([render_mesh(m, size, az, el) for az, el in views], axis=1)
            image = with_title(image, title)
            if scalar:
                image = with_colour_bar(image, lo, hi, label="value")
            write_png(os.path.join(staging, f"{name}.png"), image)
        for ext in ("ply", "glb"):
            export_mesh(pictures["after"][0], os.path.join(staging, f"result.{ext}"))
    return [
        f"filled {int(mask.sum())} vertices ({info.hole_cells} band cells) by the {method} "
        f"fill in {info.iterations} steps, {info.seconds:.2f} s",
        f"wrote {output}/before.png, after.png, result.ply, result.glb",
    ]

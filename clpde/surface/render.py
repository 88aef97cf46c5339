"""Pictures out: marching-cubes meshes with vertex colours, PLY/GLB export, and a small
headless renderer (numpy z-buffer, no matplotlib, no OpenGL) that writes PNGs.

The renderer splats points sampled on every triangle densely enough to cover its pixels,
keeps the nearest per pixel and shades them with a headlight (two-sided Lambert): simple,
vectorised and good enough for figures of smooth data on surfaces.
"""

from __future__ import annotations

import os
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike

from ..errors import InputError
from ..io.images import write_bytes

if TYPE_CHECKING:  # annotations only: trimesh is imported where a mesh is made
    import trimesh

    from .implicit import ImplicitSurface

# A perceptually ordered colour ramp (dark blue -> teal -> green -> yellow), sampled at nine
# stops and interpolated linearly: enough for pseudo-colour pictures of scalar data.
_RAMP = np.array(
    [
        [0.267, 0.005, 0.329],
        [0.278, 0.175, 0.483],
        [0.231, 0.322, 0.546],
        [0.173, 0.449, 0.558],
        [0.128, 0.567, 0.551],
        [0.153, 0.680, 0.504],
        [0.361, 0.786, 0.388],
        [0.668, 0.862, 0.196],
        [0.993, 0.906, 0.144],
    ]
)


def colormap(values: ArrayLike, vmin: float | None = None, vmax: float | None = None) -> np.ndarray:
    """RGB colours of scalar values, mapped through clpde's colour ramp.

    Parameters
    ----------
    values : array_like
        (n,) scalars (NaN allowed).
    vmin, vmax : float, optional
        The values mapped to the ramp's ends (default: the values' finite range).

    Returns
    -------
    ndarray
        (n, 3) RGB in [0, 1].

    Examples
    --------
    >>> from clpde.surface import colormap
    >>> colormap([0.0, 0.5, 1.0]).shape
    (3, 3)
    """
    v = np.asarray(values, dtype=np.float64)
    lo = np.nanmin(v) if vmin is None else vmin
    hi = np.nanmax(v) if vmax is None else vmax
    t = np.clip((v - lo) / (hi - lo if hi > lo else 1.0), 0, 1) * (len(_RAMP) - 1)
    i = np.minimum(t.astype(int), len(_RAMP) - 2)
    f = (t - i)[..., None]
    return _RAMP[i] * (1 - f) + _RAMP[i + 1] * f


def to_mesh(
    surf: ImplicitSurface,
    u: ArrayLike | None = None,
    *,
    vmin: float | None = None,
    vmax: float | None = None,
    interpolation: str = "tricubic",
) -> trimesh.Trimesh:
    """The surface as a triangle mesh (marching cubes of psi = 0) coloured by u: the
    implementation of ImplicitSurface.to_mesh, which documents the parameters."""
    import trimesh
    from skimage.measure import marching_cubes

    verts, faces, _, _ = marching_cubes(surf.psi, 0.0, spacing=(surf.spacing,) * 3)
    # marching_cubes returns (z, y, x) positions; clpde's world is (x, y, z) from the origin
    vertices = verts[:, ::-1] + surf.origin
    # skimage orients faces for ascending values (psi grows outwards): flip to point out
    mesh = trimesh.Trimesh(vertices, faces[:, ::-1], process=False)
    if u is not None:
        _colour_vertices(mesh, surf.sample(u, vertices, interpolation), vmin, vmax, "to_mesh")
    return mesh


def _colour_vertices(mesh, values, vmin, vmax, what):
    """Store sampled values on a mesh: as vertex attributes ('u' for scalars, 'u0', 'u1',
    ... per channel; a PLY keeps them as vertex properties) and as vertex colours."""
    if values.ndim == 1:
        mesh.vertex_attributes["u"] = values
        rgb = colormap(values, vmin, vmax)
    elif values.shape[1] == 3:
        for c in range(3):
            mesh.vertex_attributes[f"u{c}"] = values[:, c]
        rgb = np.clip(values, 0, 1)
    else:
        raise InputError(f"{what} colours scalar or 3-channel data, not {values.shape[1]} channels")
    mesh.visual.vertex_colors = np.concatenate(
        [np.rint(255 * rgb).astype(np.uint8), np.full((len(rgb), 1), 255, np.uint8)], axis=1
    )


def on_mesh(surf, u, mesh=None, *, vmin=None, vmax=None, interpolation="tricubic"):
    """The user's own mesh with u sampled at its vertices: a copy of `mesh` (by default
    the one `surf` was made from, ImplicitSurface.from_mesh) whose vertex attributes and
    colours hold u's values there, as `to_mesh` stores them on a marching-cubes mesh.

    The band holds u extended off the surface along its normals, and the mesh's vertices
    lie on the surface (psi = 0 there, psi being the distance to that mesh), so sampling
    the band at the vertices (`ImplicitSurface.sample`, tricubic by default, or 'trilinear')
    reads u on the surface with no remeshing: the mesh keeps its vertices, faces and order.

    Parameters
    ----------
    surf : ImplicitSurface
        The surface u lives on.
    u : array
        Data on surf's grid or band (scalar or 3 channels).
    mesh : trimesh.Trimesh, optional
        A mesh whose vertices lie within the band (default: surf's own).
    vmin, vmax : float, optional
        The colour ramp's ends for scalar data (default: the data's range).
    interpolation : str
        As for `ImplicitSurface.sample`.

    Returns
    -------
    trimesh.Trimesh
        The copy, with vertex_attributes 'u' (or 'u0'..'u2') and vertex colours.

    Raises
    ------
    InputError
        When surf was not made from a mesh and none is given, or for data of other than
        1 or 3 channels.

    Examples
    --------
    >>> import numpy as np, trimesh
    >>> from clpde.surface import ImplicitSurface
    >>> from clpde.surface.render import on_mesh
    >>> ball = trimesh.creation.icosphere(2)
    >>> surf = ImplicitSurface.from_mesh(ball, resolution=24)
    >>> result = on_mesh(surf, surf.field(lambda x, y, z: z))
    >>> len(result.vertices) == len(ball.vertices)
    True
    """
    mesh = getattr(surf, "mesh", None) if mesh is None else mesh
    if mesh is None:
        raise InputError(
            "this surface was not made from a mesh: give mesh=, or use surf.to_mesh() "
            "for a marching-cubes mesh of its zero level set"
        )
    result = mesh.copy()
    values = surf.sample(u, np.asarray(result.vertices, np.float64), interpolation)
    _colour_vertices(result, values, vmin, vmax, "on_mesh")
    return result


def export_mesh(mesh: trimesh.Trimesh, path: str | os.PathLike) -> None:
    """Write a mesh as PLY, GLB, OBJ or STL (by the path's extension), atomically.

    Parameters
    ----------
    mesh : trimesh.Trimesh
        The mesh, e.g. from `ImplicitSurface.to_mesh`; a PLY keeps its vertex colours and
        attributes.
    path : str or os.PathLike
        The file to write, ending in .ply, .glb, .obj or .stl.

    Returns
    -------
    None

    Raises
    ------
    InputError
        For another extension.

    Examples
    --------
    >>> import os, tempfile
    >>> from clpde.surface import ImplicitSurface, export_mesh
    >>> mesh = ImplicitSurface.sphere(1.0, spacing=0.1).to_mesh()
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     export_mesh(mesh, os.path.join(folder, "sphere.ply"))
    ...     os.listdir(folder)
    ['sphere.ply']
    """
    path = os.fspath(path)
    ext = os.path.splitext(path)[1].lower().lstrip(".")
    if ext not in ("ply", "glb", "obj", "stl"):
        raise InputError(f"mesh files are written as .ply, .glb, .obj or .stl, not {path!r}")
    data = mesh.export(file_type=ext)
    write_bytes(path, data if isinstance(data, bytes) else data.encode())


def _label_format(lo: float, hi: float) -> tuple[str, str]:
    """The scale's two ends as labels, rounded to a thousandth of its span: data in [0, 1]
    whose minimum is a round-off of -3e-6 reads 0 and 1, and the ends of a narrow range
    still differ."""
    span = hi - lo
    if not (np.isfinite(span) and span > 0):
        return f"{lo:.3g}", f"{hi:.3g}"
    last = int(np.floor(np.log10(span))) - 2  # the decimal exponent of the last digit shown
    step = 10.0**last

    def text(value: float) -> str:
        rounded = round(value / step) * step
        if rounded == 0:
            return "0"
        if 1e-4 <= abs(rounded) < 1e6:  # plain decimals, without trailing zeros
            plain = f"{rounded:.{max(0, -last)}f}"
            return plain.rstrip("0").rstrip(".") if "." in plain else plain
        digits = int(np.floor(np.log10(abs(rounded)))) - last + 1
        return f"{rounded:.{min(max(digits, 1), 15)}g}"

    return text(lo), text(hi)


def colour_bar(width: int, vmin: float, vmax: float, *, label: str = "") -> np.ndarray:
    """(height, width, 3) uint8 strip: the colour ramp from vmin to vmax, with the two values
    written at its ends (and `label` before them), black on white."""
    from PIL import Image, ImageDraw, ImageFont

    width = int(width)
    height = max(22, min(40, width // 12))
    font = ImageFont.load_default(size=max(10, height // 2))
    lo_text, hi_text = _label_format(float(vmin), float(vmax))
    lo_text = f"{label}:  {lo_text}" if label else lo_text
    canvas = Image.new("RGB", (width, height), (255, 255, 255))
    draw = ImageDraw.Draw(canvas)
    lo_w = draw.textlength(lo_text, font=font)
    hi_w = draw.textlength(hi_text, font=font)
    pad = max(4, height // 4)
    x0, x1 = int(lo_w + 2 * pad), int(width - hi_w - 2 * pad)
    if x1 - x0 < 16:  # too narrow for text: the ramp alone
        x0, x1, lo_text, hi_text = pad, width - pad, "", ""
    ramp = colormap(np.linspace(0.0, 1.0, x1 - x0), 0.0, 1.0)
    bar = np.rint(255 * ramp).astype(np.uint8)
    top, bottom = pad, height - pad
    strip = np.asarray(canvas).copy()
    strip[top:bottom, x0:x1] = bar[np.newaxis]
    canvas = Image.fromarray(strip)
    draw = ImageDraw.Draw(canvas)
    middle = height / 2
    draw.text((pad, middle), lo_text, fill=(0, 0, 0), font=font, anchor="lm")
    draw.text((width - pad, middle), hi_text, fill=(0, 0, 0), font=font, anchor="rm")
    return np.asarray(canvas)


def title_height(width: int) -> int:
    """The height of `with_title`'s strip over a picture `width` pixels wide."""
    return max(20, min(36, int(width) // 14))


def with_title(image, text: str) -> np.ndarray:
    """`image` with a white strip above it holding `text` (black, left-aligned)."""
    from PIL import Image, ImageDraw, ImageFont

    image = np.asarray(image)
    width = image.shape[1]
    height = title_height(width)
    font = ImageFont.load_default(size=max(10, height // 2))
    canvas = Image.new("RGB", (width, height), (255, 255, 255))
    ImageDraw.Draw(canvas).text(
        (max(4, height // 4), height / 2), text, fill=(0, 0, 0), font=font, anchor="lm"
    )
    return np.concatenate([np.asarray(canvas)[..., : image.shape[2]], image], axis=0)


def with_colour_bar(image, vmin: float, vmax: float, *, label: str = "") -> np.ndarray:
    """`image` with a colour bar from vmin to vmax below it."""
    image = np.asarray(image)
    return np.concatenate([image, colour_bar(image.shape[1], vmin, vmax, label=label)], axis=0)


def scalar_range(values, vmin=None, vmax=None) -> tuple[float, float]:
    """The range the colour ramp spans for these values, as colormap uses it."""
    v = np.asarray(values, dtype=np.float64)
    lo = float(np.nanmin(v)) if vmin is None else float(vmin)
    hi = float(np.nanmax(v)) if vmax is None else float(vmax)
    return lo, hi


def view_rotation(azimuth=30.0, elevation=20.0) -> np.ndarray:
    """Rotation taking world (x, y, z; z up) to camera (right, up, towards the viewer)."""
    a, e = np.radians(azimuth), np.radians(elevation)
    rz = np.array([[np.cos(a), -np.sin(a), 0], [np.sin(a), np.cos(a), 0], [0, 0, 1]])
    # camera looks along -y after the azimuth turn; tilt it down by the elevation
    to_cam = np.array([[1, 0, 0], [0, 0, 1], [0, -1, 0]], dtype=np.float64)
    rx = np.array([[1, 0, 0], [0, np.cos(e), -np.sin(e)], [0, np.sin(e), np.cos(e)]])
    return rx @ to_cam @ rz.T


def view_box(meshes, azimuth=30.0, elevation=20.0):
    """(centre, span) in the picture plane that holds every mesh of `meshes` seen from this
    view: given to render_mesh as `box`, several pictures share one scale and position."""
    rot = view_rotation(azimuth, elevation)
    cams = [np.asarray(m.vertices, np.float64) @ rot[:2].T for m in meshes]
    lo = np.min([c.min(axis=0) for c in cams], axis=0)
    hi = np.max([c.max(axis=0) for c in cams], axis=0)
    return 0.5 * (lo + hi), float((hi - lo).max())


def render_mesh(
    mesh: trimesh.Trimesh,
    size: int = 512,
    azimuth: float = 30.0,
    elevation: float = 20.0,
    background: tuple[float, float, float] = (1.0, 1.0, 1.0),
    box: tuple | None = None,
) -> np.ndarray:
    """A picture of a mesh with its vertex colours (light grey where it has none).

    Parameters
    ----------
    mesh : trimesh.Trimesh
        The mesh to draw.
    size : int
        The picture's width and height in pixels.
    azimuth, elevation : float
        The viewing direction in degrees.
    background : tuple of float
        The background's RGB in [0, 1].
    box : tuple, optional
        (centre, span) of the picture plane to show (`view_box`), so that several meshes
        share one scale; by default the mesh's own.

    Returns
    -------
    (size, size, 3) uint8 ndarray

    Raises
    ------
    InputError
        For a mesh without triangles.

    Examples
    --------
    >>> import trimesh
    >>> render_mesh(trimesh.creation.icosphere(1), size=32).shape
    (32, 32, 3)
    """
    verts = np.asarray(mesh.vertices, dtype=np.float64)
    faces = np.asarray(mesh.faces)
    if len(faces) == 0:
        raise InputError("the mesh has no triangles to render")
    # trimesh reports a default dark grey for meshes without colours: draw those light grey
    colours = getattr(mesh.visual, "vertex_colors", None)
    if getattr(mesh.visual, "kind", None) != "vertex":
        colours = None
    if colours is None or len(colours) != len(verts):
        colours = np.full((len(verts), 3), 0.8)
    else:
        colours = np.asarray(colours)[:, :3] / 255.0
    cam = verts @ view_rotation(azimuth, elevation).T
    if box is None:
        lo, hi = cam[:, :2].min(axis=0), cam[:, :2].max(axis=0)
        box = (0.5 * (lo + hi), float((hi - lo).max()))
    centre = np.asarray(box[0], np.float64)
    scale = 0.92 * size / max(float(box[1]), 1e-12)
    px = (cam[:, :2] - centre) * scale + size / 2
    tri_px = px[faces]
    tri_cam = cam[faces]
    # smooth shading from area-weighted vertex normals (degenerate marching-cubes slivers
    # have meaningless face normals), headlight, two-sided
    rot = view_rotation(azimuth, elevation)
    vshade = 0.25 + 0.75 * np.abs(np.asarray(mesh.vertex_normals) @ rot[2])
    edge = np.linalg.norm(tri_px[:, [1, 2, 0]] - tri_px, axis=2).max(axis=1)
    levels = np.clip(np.ceil(edge * 1.5).astype(int), 1, 256)
    depth = np.full(size * size, np.inf)
    image = np.tile(np.asarray(background, np.float64), (size * size, 1))
    for n in np.unique(levels):
        sel = np.flatnonzero(levels == n)
        i, j = np.meshgrid(np.arange(n + 1), np.arange(n + 1), indexing="ij")
        keep = i + j <= n
        w = np.stack([1 - (i[keep] + j[keep]) / n, i[keep] / n, j[keep] / n], axis=1)
        for chunk in np.array_split(sel, max(1, len(sel) * len(w) // 2_000_000 + 1)):
            p = np.einsum("kv,fvd->fkd", w, tri_px[chunk]).reshape(-1, 2)
            z = np.einsum("kv,fv->fk", w, tri_cam[chunk, :, 2]).reshape(-1)
            c = np.einsum("kv,fvd->fkd", w, colours[faces[chunk]]).reshape(-1, 3)
            c *= np.einsum("kv,fv->fk", w, vshade[faces[chunk]]).reshape(-1)[:, None]
            x = np.rint(p[:, 0]).astype(int)
            y = np.rint(size - 1 - p[:, 1]).astype(int)
            ok = (x >= 0) & (x < size) & (y >= 0) & (y < size)
            pix = y[ok] * size + x[ok]
            zz, cc = z[ok], c[ok]
            # nearest first (largest camera z is nearest the viewer), one per pixel
            order = np.lexsort((-zz, pix))
            pix, zz, cc = pix[order], zz[order], cc[order]
            first = np.ones(len(pix), bool)
            first[1:] = pix[1:] != pix[:-1]
            pix, zz, cc = pix[first], zz[first], cc[first]
            nearer = -zz < depth[pix]
            depth[pix[nearer]] = -zz[nearer]
            image[pix[nearer]] = cc[nearer]
    return np.rint(255 * np.clip(image, 0, 1)).reshape(size, size, 3).astype(np.uint8)


def render(
    surf_or_mesh: ImplicitSurface | trimesh.Trimesh,
    u: ArrayLike | None = None,
    path: str | os.PathLike | None = None,
    *,
    views: tuple[tuple[float, float], ...] = ((30.0, 20.0),),
    size: int = 512,
    vmin: float | None = None,
    vmax: float | None = None,
    colour_bar: bool = True,
) -> np.ndarray:
    """Picture(s) of data on a surface (drawn through `to_mesh`), or of a mesh with its own
    colours, side by side, written as PNG if a path is given: the implementation of
    ImplicitSurface.render, which documents the parameters."""
    import imageio.v3 as iio
    import trimesh

    mesh = (
        surf_or_mesh
        if isinstance(surf_or_mesh, trimesh.Trimesh)
        else to_mesh(surf_or_mesh, u, vmin=vmin, vmax=vmax)
    )
    views = list(views)
    if not views:
        raise InputError("give at least one (azimuth, elevation) view")
    image = np.concatenate([render_mesh(mesh, size, a, e) for a, e in views], axis=1)
    values = mesh.vertex_attributes.get("u") if hasattr(mesh, "vertex_attributes") else None
    if colour_bar and values is not None and np.ndim(values) == 1:
        image = with_colour_bar(image, *scalar_range(values, vmin, vmax))
    if path is not None:
        path = os.fspath(path)
        if not path.lower().endswith(".png"):
            raise InputError(f"render writes PNG files; give a path ending in .png, not {path!r}")
        write_bytes(path, iio.imwrite("<bytes>", image, extension=".png"))
    return image

"""Ready-made region-tracking runs (Figure 2.7's toy cases, caps on spheres, meshes coloured
by the sign of their curvature) and their outputs: one PLY per saved time and a PNG strip.
Used by `clpde regions` and the examples."""

from __future__ import annotations

import os
import warnings
from dataclasses import dataclass

import numpy as np

from .imagedata import InputError
from .regions import track_region

SCENES = ("split", "merge", "cap-expand", "cap-translate")
FLOWS = ("gaussian", "mean-curvature", "morph-sphere")


@dataclass
class Scene:
    """Inputs of one track_region run."""

    phi: np.ndarray
    region: object
    spacing: float
    origin: tuple
    options: dict


def _axes(h, extent):
    """Grid coordinates covering [-e, e] per axis (x, y, z), broadcastable."""
    axes = [np.arange(-e, e + 0.5 * h, h) for e in extent]
    return axes[0][None, None, :], axes[1][None, :, None], axes[2][:, None, None], tuple(a[0] for a in axes)


def capsule(x, y, z, half, r):
    return np.sqrt((x - np.clip(x, -half, half)) ** 2 + y**2 + z**2) - r


def two_spheres(x, y, z, c, r):
    return np.minimum(np.sqrt((x - c) ** 2 + y**2 + z**2), np.sqrt((x + c) ** 2 + y**2 + z**2)) - r


def toy_scene(name: str, spacing: float = 0.05) -> Scene:
    """Figure 2.7's toy cases and the sphere-cap checks, on a grid of the given spacing."""
    h = float(spacing)
    margin = 10 * h  # the band plus its reinitialisation ring
    if name in ("split", "merge"):
        x, y, z, origin = _axes(h, (1.25 + margin, 0.5 + margin, 0.5 + margin))
        shape = (z.size, y.size, x.size)
        if name == "split":
            start, target = capsule(x, y, z, 0.6, 0.45), two_spheres(x, y, z, 0.75, 0.45)
            region = np.sqrt(x**2 + y**2) - 0.8 + 0 * z  # a belt around the capsule's middle
        else:
            start, target = two_spheres(x, y, z, 0.55, 0.45), capsule(x, y, z, 0.6, 0.45)
            region = np.abs(x) - 0.35 + 0 * y + 0 * z  # the spheres' facing caps
        b = lambda a: np.ascontiguousarray(np.broadcast_to(a, shape))
        return Scene(b(start), b(region), h, origin,
                     {"beta": "morph", "target": b(target), "t": 4.0})
    if name in ("cap-expand", "cap-translate"):
        shift = np.array([-0.25, 0.0, -0.1]) if name == "cap-translate" else np.zeros(3)
        x, y, z, origin = _axes(h, (1.4 + margin,) * 3)
        phi = np.sqrt((x - shift[0]) ** 2 + (y - shift[1]) ** 2 + (z - shift[2]) ** 2) - 0.9
        region = np.broadcast_to(0.45 + shift[2] - z, phi.shape)  # cap of angular radius 60 deg
        options = ({"beta": 0.5, "t": 0.5} if name == "cap-expand"
                   else {"velocity": (0.5, 0.0, 0.2), "t": 1.0})
        return Scene(phi, np.ascontiguousarray(region), h, origin, options)
    raise InputError(f"scene must be one of {', '.join(SCENES)}, not {name!r}")


def curvature_sign_regions(phi, spacing, smooth=1.0):
    """Phi-hat = -(Gaussian curvature of phi's level sets), from phi smoothed by `smooth`
    cells: on the surface the region Phi-hat < 0 is where K > 0 (Figure 2.7's colours)."""
    from scipy import ndimage

    p = ndimage.gaussian_filter(np.asarray(phi, np.float64), smooth) if smooth else phi
    g = np.gradient(p, spacing)
    hess = [np.gradient(gi, spacing) for gi in g]
    # (z, y, x) axes; K = g.adj(H)g / |g|^4
    adj = np.empty((3, 3) + p.shape)
    for i in range(3):
        for j in range(3):
            a = [k for k in range(3) if k != i]
            b = [k for k in range(3) if k != j]
            minor = hess[a[0]][b[0]] * hess[a[1]][b[1]] - hess[a[0]][b[1]] * hess[a[1]][b[0]]
            adj[j, i] = (-1) ** (i + j) * minor
    gag = sum(g[i] * adj[i, j] * g[j] for i in range(3) for j in range(3))
    g2 = g[0] ** 2 + g[1] ** 2 + g[2] ** 2 + 1e-12
    return -gag / g2**2 * spacing  # scaled to about distance units near the zero


MAX_COLOUR_REGIONS = 8  # each region costs an auxiliary level set of the grid's size


def colour_labels(mesh):
    """(labels, colours): integer vertex labels from a mesh's vertex colours, one per distinct
    colour, and those colours as RGB in [0, 1]; None when it has fewer than two colours; an
    error when it has more than MAX_COLOUR_REGIONS."""
    if getattr(mesh.visual, "kind", None) != "vertex":
        return None
    rgb = np.asarray(mesh.visual.vertex_colors)[:, :3]
    colours, labels = np.unique(rgb, axis=0, return_inverse=True)
    if len(colours) < 2:
        return None
    if len(colours) > MAX_COLOUR_REGIONS:
        raise InputError(
            f"the mesh has {len(colours)} vertex colours; as regions it may have at most "
            f"{MAX_COLOUR_REGIONS} (paint each region in one flat colour), or use --regions curvature")
    return labels.reshape(-1), colours / 255.0


def mesh_scene(path, flow="gaussian", resolution=96, t=None, regions="auto") -> Scene:
    """A mesh file's surface evolved by the positive part of the Gaussian curvature, mean
    curvature, or morphing to a sphere, with regions from its vertex colours (one region per
    flat colour: regions='colours', or 'auto' when it has some) or else the sign of its
    Gaussian curvature (regions='curvature')."""
    from .surface import ImplicitSurface

    if flow not in FLOWS:
        raise InputError(f"flow must be one of {', '.join(FLOWS)}, not {flow!r}")
    if regions not in ("auto", "colours", "curvature"):
        raise InputError(f"regions must be 'auto', 'colours' or 'curvature', not {regions!r}")
    from .surface.demo import encloses_volume

    if isinstance(path, (str, os.PathLike)) and not os.path.exists(path):
        raise InputError(f"the mesh file {path} does not exist")
    with encloses_volume(path):
        surf = ImplicitSurface.from_mesh(path, resolution=resolution, band=12.0)
    phi, h, origin = surf.psi, surf.spacing, tuple(surf.origin)
    painted = None
    if regions == "colours":
        painted = colour_labels(surf.mesh)
    elif regions == "auto":
        try:
            painted = colour_labels(surf.mesh)
        except InputError as exc:  # shaded or photographed colours are no regions
            warnings.warn(f"{exc}; tracking the curvature-sign regions instead", stacklevel=2)
    if painted is None and regions == "colours":
        raise InputError(f"{path} has no vertex colours to take regions from; use --regions curvature")
    region = painted[0] if painted is not None else curvature_sign_regions(phi, h)
    if flow == "gaussian":
        # weight h^3: speed K+ in cells per unit time (K in 1 / cells^2); creases sharper
        # than a 2-cell radius move at that radius' speed
        options = {"beta": "gaussian", "weight": h**3, "max_speed": 0.25 * h,
                   "t": t if t is not None else 60.0}
    elif flow == "mean-curvature":
        # about 15 curvature-limited steps' worth: a few cells of motion on curved parts
        options = {"beta": "mean-curvature", "t": t if t is not None else 15 * h**2}
    else:
        # morph toward the sphere of the same volume around the shape's centroid
        x, y, z = surf.coordinates()
        inside = phi < 0
        weights = inside / inside.sum()
        centre = [float((np.broadcast_to(a, phi.shape) * weights).sum()) for a in (x, y, z)]
        radius = np.cbrt(3 * inside.sum() * h**3 / (4 * np.pi))
        target = np.sqrt((x - centre[0]) ** 2 + (y - centre[1]) ** 2 + (z - centre[2]) ** 2) - radius
        options = {"beta": "morph", "target": np.broadcast_to(target, phi.shape).copy(),
                   "t": t if t is not None else 3.0}
    if painted is not None:  # the regions keep the mesh's colours
        options["mesh"], options["palette"] = surf.mesh, painted[1]
    return Scene(phi, region, h, origin, options)


def displacement(scene: Scene, frame) -> float:
    """How far (world units) the surface of `frame` lies from the scene's starting surface
    at most: the starting signed distance at the frame's mesh vertices."""
    from scipy.ndimage import map_coordinates

    at = (np.asarray(frame.mesh.vertices) - np.asarray(scene.origin)) / scene.spacing
    return float(np.abs(map_coordinates(np.asarray(scene.phi, np.float64), at[:, ::-1].T,
                                        order=1, mode="nearest")).max())


def run_scene(scene: Scene, saves=4, progress=None, device=None):
    return track_region(scene.phi, scene.region, spacing=scene.spacing, saves=saves,
                        origin=scene.origin, progress=progress, device=device, **scene.options)


def write_frames(frames, outdir, size=256, views=((30.0, 20.0),), stem="regions",
                 overwrite=False):
    """OUTDIR/<stem>_<k>.ply per frame and OUTDIR/<stem>.png: frames top to bottom, views
    side by side, as a 128-colour palette PNG (two shaded colours on white: no visible loss,
    2.5x smaller than RGB). OUTDIR is created if missing; an existing one must be empty, or
    with overwrite=True hold only clpde's kinds of output files, and is then replaced as a
    whole (clpde.io.output_folder). Returns the paths written."""
    from .io import output_folder

    with output_folder(outdir, overwrite) as staging:
        written = _write_frame_files(frames, str(staging), size, views, stem)
    return [os.path.join(outdir, os.path.basename(p)) for p in written]


def _write_frame_files(frames, outdir, size, views, stem):
    import io

    from PIL import Image

    from .surface.render import _atomic_write, export_mesh, render_mesh

    written = []
    rows = []
    for k, frame in enumerate(frames):
        path = os.path.join(outdir, f"{stem}_{k}.ply")
        export_mesh(frame.mesh, path)
        written.append(path)
        rows.append(np.concatenate([render_mesh(frame.mesh, size, a, e) for a, e in views], axis=1))
    picture = np.concatenate(rows, axis=0)
    path = os.path.join(outdir, f"{stem}.png")
    palette = Image.fromarray(np.ascontiguousarray(picture[..., :3])).quantize(
        colors=128, method=Image.Quantize.MEDIANCUT, dither=Image.Dither.NONE)
    data = io.BytesIO()
    palette.save(data, format="PNG", optimize=True)
    _atomic_write(path, data.getvalue())
    written.append(path)
    return written

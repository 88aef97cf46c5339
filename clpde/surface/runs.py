"""The chapter-4 flows as ready-made runs on a shape or a user's mesh (`load_surface`,
`run_flow`), returning the data before and after on the surface, written as pictures (PNG)
and a coloured mesh (PLY, GLB) into an output folder (`write_run`). `clpde surface` and the
examples run them. The demonstration data is in shapes.py."""

from __future__ import annotations

import os
import warnings
from dataclasses import dataclass

import numpy as np

from ..errors import InputError
from ..io.images import output_folder, write_bytes
from .implicit import ImplicitSurface
from .mesh_sdf import encloses_volume
from .render import (
    export_mesh,
    on_mesh,
    render_mesh,
    scalar_range,
    with_colour_bar,
    with_title,
)
from .shapes import SURFACE_SHAPES as SHAPES
from .shapes import checker, colour_pattern, surface_noise, surface_shape

FLOWS = ("heat", "tv", "denoise", "chroma", "reaction-diffusion", "flowvis", "curvature")


def load_surface(mesh, resolution=96, device=None) -> ImplicitSurface:
    """A generated shape by name (clpde.surface.SURFACE_SHAPES) or a mesh file / Trimesh,
    at about `resolution` cells across."""
    if isinstance(mesh, str) and mesh in SHAPES:
        return surface_shape(mesh, resolution, device=device)
    if isinstance(mesh, str) and not os.path.exists(mesh):
        raise InputError(
            f"{mesh!r} is neither a mesh file nor one of the shapes {', '.join(SHAPES)}"
        )
    with encloses_volume(mesh):
        return ImplicitSurface.from_mesh(mesh, resolution=resolution, device=device)


@dataclass
class SurfaceRun:
    flow: str
    surface: ImplicitSurface
    before: np.ndarray | None  # None: the bare surface
    after: np.ndarray
    note: str
    label: str = ""  # what a scalar `after` is, for its colour bar
    span: float = 0.0  # least width of a scalar's colour scale, so near-constants look flat


def mesh_colours(surf):
    """The vertex colours of the mesh `surf` was built from, carried to the band as RGB in
    [0, 1], shape (3, nz, ny, nx); None when the mesh has none (or all vertices alike)."""
    mesh = getattr(surf, "mesh", None)
    if mesh is None or getattr(mesh.visual, "kind", None) != "vertex":
        return None
    rgb = np.asarray(mesh.visual.vertex_colors)[:, :3]
    if len(rgb) != len(mesh.vertices) or np.all(rgb == rgb[0]):
        return None
    return surf.field_from_mesh(rgb / 255.0)


DATA_FLOWS = ("heat", "tv", "denoise", "chroma")  # the flows that can take the user's colours


def run_flow(
    surf,
    flow,
    *,
    t=None,
    iterations=None,
    sigma=0.15,
    seed=0,
    direction="major",
    data=None,
    progress=None,
) -> SurfaceRun:
    """Run one of FLOWS with the thesis' settings; returns the data before and after.

    data: the user's values on the band (e.g. mesh_colours(surf)) for heat, tv, denoise and
    chroma, processed as they are (sigma is then their noise level for denoise). Without
    it these flows make the figures' demonstration data: a checkerboard or a colour pattern,
    with noise of sigma added for tv, denoise and chroma."""
    rng = np.random.default_rng(seed)
    h = surf.spacing
    size = h * max(surf.shape)
    if data is not None:
        return _run_on_data(surf, flow, np.asarray(data), t, sigma, progress)
    if flow == "heat":  # Figure 4.3: intrinsic isotropic diffusion of an image
        before = checker(surf)
        t = 2e-4 * size**2 if t is None else t
        return SurfaceRun(
            flow, surf, before, surf.heat(before, t=t, progress=progress), f"heat flow to t={t:g}"
        )
    if flow == "tv":  # Figure 4.4 right: anisotropic diffusion without a stopping term
        before = checker(surf) + surface_noise(surf, sigma, rng)
        t = tv_time(sigma, h) if t is None else t
        return SurfaceRun(
            flow, surf, before, surf.tv(before, t=t, progress=progress), f"TV flow to t={t:g}"
        )
    if flow == "denoise":  # Figure 4.4 middle: TV with fidelity and dynamic lambda
        before = checker(surf) + surface_noise(surf, sigma, rng)
        t = 40 * h**2 if t is None else t
        after, info = surf.denoise_tv(before, sigma=sigma, t=t, return_info=True, progress=progress)
        return SurfaceRun(
            flow,
            surf,
            before,
            after,
            f"TV denoising, sigma={sigma:g}: residual variance "
            f"{info.residual_variance:.4g} (sigma^2 = {sigma**2:.4g})",
        )
    if flow == "chroma":  # Figure 4.6: chroma by harmonic maps (p = 1), brightness by TV
        clean = colour_pattern(surf)
        before = np.clip(clean + surface_noise(surf, sigma, rng, channels=3), 0.01, 1)
        t = 4 * h**2 if t is None else t
        return SurfaceRun(
            flow,
            surf,
            before,
            surf.denoise_colour(before, t=t, progress=progress),
            f"chroma harmonic map p=1 and brightness TV flow to t={t:g}",
        )
    if flow in ("reaction-diffusion", "flowvis", "curvature"):
        major, minor, curv = surf.principal_directions()
        field = {"major": major, "minor": minor}.get(direction)
        if field is None:
            raise InputError(f"direction must be 'major' or 'minor', not {direction!r}")
        if flow == "curvature":
            mean, scale = _mean_curvature(surf, 0.5 * (curv[0] + curv[1]), progress)
            note = "mean curvature (principal curvatures / 2)"
            if scale:
                note += f", averaged along the surface over {scale:.3g} (the mesh's edge length)"
            # a sphere's curvature is one value: a scale of at least half its size keeps
            # the last percent of discretisation error from filling the colour ramp
            typical = float(np.median(np.abs(mean[np.abs(surf.psi) < surf.spacing])))
            return SurfaceRun(flow, surf, None, mean, note, "mean curvature", 0.5 * typical)
        if flow == "flowvis":  # Figure 4.8: noise diffused along a principal direction
            before = surf.field(lambda x, y, z: 0 * x) + rng.random(surf.shape)
            t = 10 * h**2 if t is None else t
            after = surf.diffuse_along(before, field, t=t, progress=progress)
            return SurfaceRun(
                flow,
                surf,
                before,
                after,
                f"noise diffused along the {direction} principal direction to t={t:g}",
            )
        iterations = 4000 if iterations is None else iterations
        along = field if direction != "none" else None
        ab = surf.reaction_diffusion(iterations, direction=along, seed=seed, progress=progress)
        return SurfaceRun(
            flow,
            surf,
            np.full(surf.shape, 4.0),
            ab[0],
            f"reaction-diffusion (Figure 4.7's numbers), {iterations} iterations, "
            "diffusion of a "
            f"along the {direction} direction"
            if along is not None
            else f"reaction-diffusion (Figure 4.7's numbers), {iterations} iterations",
            "chemical a",
        )
    raise InputError(f"unknown surface flow {flow!r}; choose one of {', '.join(FLOWS)}")


# The averaging width, as a share of the mesh's bounding-box diagonal, above which the
# averaged curvature no longer tells the shape's parts apart: wider than about a sixth of
# the shape, one average covers a face and the edges around it (the shares of common
# meshes are in docs/surface.md).
COARSE_SHARE = 0.15


def warn_if_too_coarse(mesh, sigma: float) -> bool:
    """Warn (UserWarning) when the curvature's averaging width `sigma` (the mesh's median
    edge length, or two cells) spans more than COARSE_SHARE of the mesh's size: the mesh
    then has too few vertices to say where its curvature lies, and the average spreads the
    curvature of its edges and corners over its faces. Returns whether it warned."""
    diagonal = float(np.linalg.norm(np.ptp(np.asarray(mesh.vertices), axis=0)))
    share = sigma / max(diagonal, 1e-300)
    if share <= COARSE_SHARE:
        return False
    warnings.warn(
        f"the mesh is too coarse for curvature: {len(mesh.faces)} faces, so the curvature "
        f"is averaged over {sigma:.3g} ({share:.0%} of its size), which spreads its edges' "
        "and corners' curvature over its faces (flat faces do not read 0); give a finer "
        "mesh (e.g. trimesh's mesh.subdivide_to_size) for curvature",
        UserWarning,
        stacklevel=3,
    )
    return True


def tv_time(sigma, h):
    """How long TV flow (no fidelity) runs by default: sigma * h. TV flow moves a level set at
    its curvature, so a bump of contrast c and width w flattens in a time of about c * w:
    noise of deviation sigma at the grid's scale goes in sigma * h, while the checkerboard's
    squares, a hundred times larger, keep their flat values and sharp edges. (40 h^2, the
    earlier default, is 8 sigma h at 96 cells: it rounded the squares into blobs, which
    looked like heat; docs/surface.md compares the two.)"""
    return float(sigma) * h


def _mean_curvature(surf, mean, progress=None):
    """(mean curvature, smoothing scale or 0). A mesh's psi is the distance to its flat
    triangles, whose curvature sits on their edges and vertices: the values seen at the
    grid's scale are spikes along the tessellation. Averaging them along the surface by
    heat flow over a width sigma of at least two cells, or the mesh's median edge length
    if longer (t = sigma^2 / 2), leaves the curvature of the shape the mesh samples
    (docs/surface.md has an icosphere's spread before and after). Analytic shapes are kept
    as computed."""
    mesh = getattr(surf, "mesh", None)
    if mesh is None:
        return mean, 0.0
    sigma = max(2.0 * surf.spacing, float(np.median(mesh.edges_unique_length)))
    warn_if_too_coarse(mesh, sigma)
    return surf.heat(mean, t=0.5 * sigma**2, progress=progress), sigma


def _run_on_data(surf, flow, data, t, sigma, progress) -> SurfaceRun:
    h = surf.spacing
    if flow not in DATA_FLOWS:
        raise InputError(
            f"the {flow} flow makes its own data; only {', '.join(DATA_FLOWS)} take yours"
        )
    if flow == "chroma" and data.shape[:1] != (3,):
        raise InputError("chroma denoising needs colour (3-channel) data")
    if flow == "heat":
        t = 2e-4 * (h * max(surf.shape)) ** 2 if t is None else t
        return SurfaceRun(
            flow,
            surf,
            data,
            surf.heat(data, t=t, progress=progress),
            f"heat flow of the mesh's data to t={t:g}",
        )
    if flow == "tv":
        t = tv_time(sigma, h) if t is None else t
        return SurfaceRun(
            flow,
            surf,
            data,
            surf.tv(data, t=t, progress=progress),
            f"TV flow of the mesh's data to t={t:g}",
        )
    if flow == "denoise":
        t = 40 * h**2 if t is None else t
        after, info = surf.denoise_tv(data, sigma=sigma, t=t, return_info=True, progress=progress)
        return SurfaceRun(
            flow,
            surf,
            data,
            after,
            f"TV denoising of the mesh's data for noise sigma={sigma:g}: residual "
            f"variance {info.residual_variance:.4g}",
        )
    t = 4 * h**2 if t is None else t
    return SurfaceRun(
        flow,
        surf,
        data,
        surf.denoise_colour(data, t=t, progress=progress),
        f"the mesh's colours: chroma harmonic map p=1 and brightness TV flow to t={t:g}",
    )


def write_run(
    run: SurfaceRun,
    outdir,
    *,
    views=((30.0, 25.0), (210.0, 25.0)),
    size=400,
    overwrite=False,
    on_input=False,
) -> list:
    """before.png, after.png, result.ply and result.glb (after, coloured) in the folder
    outdir, created if missing; an existing one must be empty, or with overwrite=True hold
    only clpde's kinds of output files, and is then replaced as a whole
    (clpde.io.output_folder). on_input: the meshes are the one the surface was made from,
    with the values sampled at its vertices (render.on_mesh); else marching-cubes meshes
    of the surface. The pictures are titled and scalar ones carry their colour scale.
    Returns the paths."""
    with output_folder(outdir, overwrite) as staging:
        names = _write_run_files(run, staging, views, size, on_input)
    return [os.path.join(outdir, n) for n in names]


def _write_run_files(run: SurfaceRun, outdir, views, size, on_input=False) -> list:
    def make(u, **options):
        if on_input:
            return on_mesh(run.surface, u, **options) if u is not None else run.surface.mesh.copy()
        return run.surface.to_mesh(u, **options)

    written = []
    after = make(run.after)
    scalar = run.after.ndim == 3
    lo = hi = None
    if scalar:  # one colour scale (the result's) for both pictures, shown by a colour bar
        lo, hi = scalar_range(after.vertex_attributes["u"])
        if hi - lo < run.span:
            middle = 0.5 * (lo + hi)
            lo, hi = middle - 0.5 * run.span, middle + 0.5 * run.span
        after = make(run.after, vmin=lo, vmax=hi)
    before = make(run.before, vmin=lo, vmax=hi)
    where = (
        f"on the input mesh ({len(after.vertices)} vertices)"
        if on_input
        else f"on a marching-cubes mesh ({len(after.vertices)} vertices)"
    )
    titles = {
        "before": f"before: the {run.flow} flow's input, {where}",
        "after": f"after: {run.note}",
    }
    for name, mesh in (("before", before), ("after", after)):
        image = np.concatenate([render_mesh(mesh, size, a, e) for a, e in views], axis=1)
        image = with_title(image, titles[name])
        if scalar and (name == "after" or run.before is not None):
            image = with_colour_bar(image, lo, hi, label=run.label)
        write_png(os.path.join(outdir, f"{name}.png"), image)
        written.append(f"{name}.png")
    for ext in ("ply", "glb"):
        export_mesh(after, os.path.join(outdir, f"result.{ext}"))
        written.append(f"result.{ext}")
    return written


def write_png(path, image) -> None:
    """An RGB(A) uint8 picture as a PNG file, written atomically."""
    import imageio.v3 as iio

    write_bytes(path, iio.imwrite("<bytes>", image, extension=".png"))

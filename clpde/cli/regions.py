"""`clpde regions`: region tracking on a deforming surface (clpde.regions).

Besides the subcommand: the scenes of a user's mesh file (`mesh_scene`), running a scene
(`run_scene`) and writing its frames as meshes and a picture (`write_frames`), which the
examples use too. The named toy scenes are `clpde.data.region_scene`."""

from __future__ import annotations

import os
import sys
import warnings

import numpy as np

from ..data import REGION_SCENES as SCENES
from ..data import RegionScene, region_scene
from ..errors import InputError
from ..io.images import output_folder, write_bytes
from ..regions.api import track_region
from ..regions.mesh import surface_mesh
from ..runtime import get_runtime
from ..surface import ImplicitSurface
from ..surface.render import export_mesh, render_mesh, view_box, with_title
from ..surface.runs import encloses_volume
from ._common import (
    add_device_argument,
    add_output_folder_arguments,
    check_output_folder_args,
    grid_advice,
    show_progress,
)

FLOWS = ("gaussian", "mean-curvature", "morph-sphere")
# The default motion of a mesh file: morphing toward the sphere of its volume moves every
# shape but a sphere by a visible share of its size (benchmarks/regions_mesh_motion.py),
# where the Gaussian-curvature flow barely moves smooth meshes.
DEFAULT_FLOW = "morph-sphere"


def add_regions_parser(subparsers) -> None:
    parser = subparsers.add_parser(
        "regions",
        help="track painted regions on a deforming surface (thesis 2.2)",
        description="Track regions on a surface that deforms by level sets (thesis section "
        "2.2). SCENE is one of " + ", ".join(SCENES) + " (Figure 2.7's toy cases "
        "and caps on a sphere), or a mesh file: its surface evolves by --flow, with "
        "regions from its vertex colours or the sign of its Gaussian curvature. "
        "Writes OUTDIR/regions_K.ply per saved time (per-vertex region colours) "
        "and OUTDIR/regions.png (saved times top to bottom).",
    )
    parser.add_argument("scene", metavar="SCENE", help="scene name or mesh file")
    add_output_folder_arguments(parser)
    parser.add_argument(
        "--flow",
        choices=FLOWS,
        default=DEFAULT_FLOW,
        help="surface motion for a mesh file: morph-sphere (default) morphs it "
        "toward the sphere of its volume; mean-curvature shrinks it; "
        "gaussian moves it by the positive part of its Gaussian curvature "
        "(creases and folds). The grid grows to hold where the flow takes "
        "the surface; the output says how far it moved",
    )
    parser.add_argument(
        "--regions",
        choices=("auto", "colours", "curvature"),
        default="auto",
        help="regions on a mesh file: one per flat vertex colour ('colours'), "
        "or where its Gaussian curvature is positive ('curvature'); "
        "'auto' (default) takes the colours when the mesh has them",
    )
    parser.add_argument(
        "--spacing",
        type=float,
        default=0.05,
        help="grid spacing of the named scenes (default: 0.05)",
    )
    parser.add_argument(
        "--resolution",
        type=int,
        default=96,
        help="grid cells across a mesh's longest side (default: 96)",
    )
    parser.add_argument("--t", type=float, default=None, help="final time (default: per scene)")
    parser.add_argument("--saves", type=int, default=4, help="saved intervals (default: 4)")
    parser.add_argument(
        "--size", type=int, default=256, help="picture size per view (default: 256)"
    )
    add_device_argument(parser)
    parser.set_defaults(run=run_regions)


def run_regions(args) -> int:
    get_runtime(args.device)
    check_output_folder_args(args, [] if args.scene in SCENES else [args.scene])
    if args.size < 16:
        raise InputError(f"--size must be at least 16, not {args.size}")
    if args.scene not in SCENES and not os.path.exists(args.scene):
        raise InputError(
            f"{args.scene!r} is neither a mesh file nor one of the scenes {', '.join(SCENES)}"
        )
    if args.scene in SCENES:
        scene = region_scene(args.scene, args.spacing)
        if args.t is not None:
            scene.options["t"] = args.t
    else:
        if show_progress():  # the grid and the regions take a while before the steps begin
            print(
                f"regions: building a grid of {args.resolution} cells across {args.scene} "
                "and its regions...",
                file=sys.stderr,
                flush=True,
            )
        with grid_advice(args.resolution):
            scene = mesh_scene(args.scene, args.flow, args.resolution, args.t, args.regions)
    frames = run_scene(scene, saves=args.saves, progress=show_progress(), device=args.device)
    written = write_frames(
        frames,
        args.output,
        size=args.size,
        views=((30.0, 25.0), (-60.0, 35.0)),
        overwrite=args.overwrite,
    )
    share = ", ".join(f"{f.area_fraction(0):.3f}" for f in frames)
    print(
        f"regions {args.scene}: grid {'x'.join(map(str, scene.phi.shape[::-1]))}, region 0 "
        f"area fraction {share} at t = {', '.join(f'{f.time:g}' for f in frames)}; wrote "
        f"{len(written)} files to {args.output}",
        file=sys.stderr,
    )
    if args.scene not in SCENES:
        print(motion_report(scene, frames, args.flow), file=sys.stderr)
    return 0


def motion_report(scene: RegionScene, frames, flow: str) -> str:
    """One line saying how far the surface moved, from what was measured: the mean and
    largest distance of the last frame's vertices from the starting surface, and, when it
    hardly moved, the measured reason and what to change."""
    mean, most = displacement_stats(scene, frames[-1], frames[0].mesh)
    diagonal = float(np.linalg.norm(np.ptp(np.asarray(frames[0].mesh.vertices), axis=0)))
    line = (
        f"regions: the surface moved {mean / diagonal:.1%} of its size on average (mean "
        f"vertex displacement / bounding-box diagonal), at most {most / scene.spacing:.2f} "
        f"grid cells; area {frames[0].area():.4g} -> {frames[-1].area():.4g}"
    )
    if most / scene.spacing >= 1.0:
        return line
    if flow == "gaussian":
        curvature = frames[0].mesh.vertex_defects  # angle defects: Gaussian curvature x area
        share = float(np.mean(curvature > 1e-3)) if len(curvature) else 0.0
        why = (
            f"--flow gaussian moves only where the Gaussian curvature is positive and large "
            f"(creases, folds); here {share:.0%} of the vertices have a positive angle "
            "defect and none is sharp enough to move it; --flow morph-sphere (the "
            "default) moves any shape but a sphere, or give a larger --t"
        )
    elif flow == "mean-curvature":
        why = (
            "give a larger --t (a sphere of radius R shrinks by about 2t/R), or --flow morph-sphere"
        )
    else:
        why = (
            "its shape is already within a cell of the sphere of its volume; --flow "
            "mean-curvature with a larger --t shrinks it"
        )
    return f"{line}: it hardly moved. {why}"


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
            f"{MAX_COLOUR_REGIONS} (paint each region in one flat colour), or use --regions "
            "curvature"
        )
    return labels.reshape(-1), colours / 255.0


def mesh_scene(path, flow=DEFAULT_FLOW, resolution=96, t=None, regions="auto") -> RegionScene:
    """A mesh file's surface evolved by the positive part of the Gaussian curvature, mean
    curvature, or morphing to a sphere, with regions from its vertex colours (one region per
    flat colour: regions='colours', or 'auto' when it has some) or else the sign of its
    Gaussian curvature (regions='curvature')."""

    if flow not in FLOWS:
        raise InputError(f"flow must be one of {', '.join(FLOWS)}, not {flow!r}")
    if regions not in ("auto", "colours", "curvature"):
        raise InputError(f"regions must be 'auto', 'colours' or 'curvature', not {regions!r}")
    if isinstance(path, (str, os.PathLike)) and not os.path.exists(path):
        raise InputError(f"the mesh file {path} does not exist")
    with encloses_volume(path):
        surf = ImplicitSurface.from_mesh(path, resolution=resolution, band_width=12.0)
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
        raise InputError(
            f"{path} has no vertex colours to take regions from; use --regions curvature"
        )
    if flow == "morph-sphere":
        # the sphere of the same volume around the shape's centroid: the volume must hold it
        # as well as the mesh, with the band's margin around both (a flat torus morphs into
        # a sphere taller than its own bounding box)
        x, y, z = surf.coordinates()
        inside = phi < 0
        weights = inside / inside.sum()
        centre = np.array(
            [float((np.broadcast_to(a, phi.shape) * weights).sum()) for a in (x, y, z)]
        )
        radius = float(np.cbrt(3 * inside.sum() * h**3 / (4 * np.pi)))
        phi, origin = pad_to_hold(phi, h, origin, centre - radius, centre + radius, MARGIN_CELLS)
    elif flow == "gaussian":
        # K+ flow moves at most max_speed * t: room for that on every side
        phi, origin = pad_to_hold(
            phi, h, origin, *_bounds(surf.mesh), MARGIN_CELLS + 0.25 * (60.0 if t is None else t)
        )
    region = painted[0] if painted is not None else curvature_sign_regions(phi, h)
    if flow == "gaussian":
        # weight h^3: speed K+ in cells per unit time (K in 1 / cells^2); creases sharper
        # than a 2-cell radius move at that radius' speed
        options = {
            "beta": "gaussian",
            "weight": h**3,
            "max_speed": 0.25 * h,
            "t": t if t is not None else 60.0,
        }
    elif flow == "mean-curvature":
        # about 15 curvature-limited steps' worth: a few cells of motion on curved parts.
        # Mean-curvature flow stays inside the starting bounding box: no padding needed.
        options = {"beta": "mean-curvature", "t": t if t is not None else 15 * h**2}
    else:
        nz, ny, nx = phi.shape
        zz, yy, xx = np.meshgrid(
            *(origin[a] + h * np.arange(n) for a, n in ((2, nz), (1, ny), (0, nx))),
            indexing="ij",
            sparse=True,
        )
        target = (
            np.sqrt((xx - centre[0]) ** 2 + (yy - centre[1]) ** 2 + (zz - centre[2]) ** 2) - radius
        )
        options = {
            "beta": "morph",
            "target": np.broadcast_to(target, phi.shape).copy(),
            "t": t if t is not None else 3.0,
        }
    if painted is not None:  # the regions keep the mesh's colours
        options["mesh"], options["palette"] = surf.mesh, painted[1]
    return RegionScene(phi, region, h, origin, options)


# Cells kept between the surface, wherever the flow may take it, and the volume's border:
# the tracker's band (band_width 5) and its reinitialisation ring refuse to come within
# about 8 cells, and the mesh's own grid leaves 16.
MARGIN_CELLS = 16.0


def _bounds(mesh):
    lo, hi = np.asarray(mesh.bounds, np.float64)
    return lo, hi


def pad_to_hold(phi, spacing, origin, lo, hi, margin_cells):
    """(phi, origin) grown so that the world box [lo, hi] (x, y, z) has `margin_cells` cells
    of room on every side. The new cells take the value of the border cells next to them:
    far from the surface a mesh's psi holds its capped distance (the same value everywhere
    outside the band), so edge values are what the grid would have held there."""
    phi = np.asarray(phi)
    origin = np.asarray(origin, np.float64)
    nz, ny, nx = phi.shape
    top = origin + spacing * (np.array([nx, ny, nz]) - 1)
    before = np.ceil((origin - (np.asarray(lo) - margin_cells * spacing)) / spacing)
    after = np.ceil(((np.asarray(hi) + margin_cells * spacing) - top) / spacing)
    before, after = np.maximum(before, 0).astype(int), np.maximum(after, 0).astype(int)
    if not before.any() and not after.any():
        return phi, tuple(origin)
    widths = [(before[2], after[2]), (before[1], after[1]), (before[0], after[0])]
    return np.pad(phi, widths, mode="edge"), tuple(origin - spacing * before)


def displacement(scene: RegionScene, frame) -> float:
    """How far (world units) the surface of `frame` lies from the scene's starting surface
    at most: the starting signed distance at the frame's mesh vertices."""
    return displacement_stats(scene, frame)[1]


def displacement_stats(scene: RegionScene, frame, start=None) -> tuple[float, float]:
    """(mean, largest) displacement of the surface, world units.

    mean: the starting surface's vertices' mean distance to `frame`'s surface (how far the
    vertices moved along the normals), with both surfaces as meshes (the start: `start`, by
    default the marching-cubes mesh of the scene's phi), nearest vertex to vertex: within
    half a cell of the distance to the surface. largest: the farthest of `frame`'s vertices
    from the starting surface, read from the starting signed distance (trilinear) where it
    is a distance (a mesh's psi is capped past its band; there the nearest starting vertex
    is taken instead)."""
    from scipy.ndimage import map_coordinates
    from scipy.spatial import cKDTree

    phi = np.asarray(scene.phi, np.float64)
    if start is None:
        start = surface_mesh(phi, scene.spacing, scene.origin)
    begin = np.asarray(start.vertices, np.float64)
    points = np.asarray(frame.mesh.vertices, np.float64)
    mean = float(cKDTree(points).query(begin)[0].mean())
    at = (points - np.asarray(scene.origin)) / scene.spacing
    d = np.abs(map_coordinates(phi, at[:, ::-1].T, order=1, mode="nearest"))
    far = d > 0.9 * np.abs(phi).max()
    if far.any():
        d[far] = cKDTree(begin).query(points[far])[0]
    return mean, float(d.max())


def run_scene(scene: RegionScene, saves=4, progress=None, device=None):
    return track_region(
        scene.phi,
        scene.region,
        spacing=scene.spacing,
        saves=saves,
        origin=scene.origin,
        progress=progress,
        device=device,
        **scene.options,
    )


def write_frames(frames, outdir, size=256, views=((30.0, 20.0),), stem="regions", overwrite=False):
    """OUTDIR/<stem>_<k>.ply per frame and OUTDIR/<stem>.png: frames top to bottom, views
    side by side, as a 128-colour palette PNG (two shaded colours on white: no visible loss,
    smaller than RGB; docs/regions.md). OUTDIR is created if missing; an existing one must
    be empty, or with overwrite=True hold only clpde's kinds of output files, and is then
    replaced as a whole (clpde.io.output_folder). Returns the paths written."""

    with output_folder(outdir, overwrite) as staging:
        written = _write_frame_files(frames, str(staging), size, views, stem)
    return [os.path.join(outdir, os.path.basename(p)) for p in written]


def _region_count(frame) -> int:
    """The number of regions a frame tracks (its first labels), at most three for a title."""
    labels = np.asarray(frame.face_labels)
    return int(min(3, max(1, labels.max(initial=0) + 1)))


def _write_frame_files(frames, outdir, size, views, stem):
    import io

    from PIL import Image

    written = []
    rows = []
    # one scale and position per view for every row, so that growth and shrinking show
    boxes = [view_box([f.mesh for f in frames], a, e) for a, e in views]
    for k, frame in enumerate(frames):
        path = os.path.join(outdir, f"{stem}_{k}.ply")
        export_mesh(frame.mesh, path)
        written.append(path)
        row = np.concatenate(
            [
                render_mesh(frame.mesh, size, a, e, box=box)
                for (a, e), box in zip(views, boxes, strict=True)
            ],
            axis=1,
        )
        area = ", ".join(
            f"region {label}: {frame.area_fraction(label):.1%}"
            for label in range(_region_count(frame))
        )
        rows.append(
            with_title(row, f"t = {frame.time:.4g}" + (f"   ({area} of the area)" if area else ""))
        )
    picture = np.concatenate(rows, axis=0)
    path = os.path.join(outdir, f"{stem}.png")
    palette = Image.fromarray(np.ascontiguousarray(picture[..., :3])).quantize(
        colors=128, method=Image.Quantize.MEDIANCUT, dither=Image.Dither.NONE
    )
    data = io.BytesIO()
    palette.save(data, format="PNG", optimize=True)
    write_bytes(path, data.getvalue())
    written.append(path)
    return written

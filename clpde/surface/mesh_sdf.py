"""Triangle mesh -> signed distance volume, fast enough for 128^3-256^3 grids.

Magnitude: the unsigned distance to the mesh in the band. Points sampled every half cell on
the triangles mark the cells the surface crosses (keeping two crossing triangles per cell);
a Euclidean distance transform gives every cell its nearest crossed cell, and the exact
point-triangle distance to that cell's triangles is taken. Cells beyond the band get the
band's cap, with their sign. (A k-d tree over the samples was slower: docs/surface.md.)

Sign: a flood fill, checked and repaired by the generalized winding number. The cells
closer than half a cell to the mesh form a shell that no 6-connected path crosses where the
mesh is closed (holes smaller than a cell are sealed, and the orientation of the faces does
not matter); a flood fill from the box's border through the other cells finds the outside,
and the other components of the fill are inside. Then the winding number w (winding.cl:
the sum of the triangles' solid angles / 4 pi, with a two-level far-field expansion; the
faces are made consistently oriented first, on a copy, and |w| > 1/2 is inside, so a mesh
turned inside out works too) is evaluated at a sample of cells of every component: a
component whose samples agree takes their side. One that leaked, through a hole wider than
a cell (a border component with samples inside, or samples on both sides), is decided cell
by cell: each band cell by its own w, the cells beyond the band by w on a lattice of up to
4 cells' spacing (w is smooth that far from the mesh). Across a hole w falls smoothly
through 1/2, so the sign changes on a sheet spanning the hole; |psi| stays the distance to
the mesh, there the distance to the hole's rim (ImplicitSurface.from_mesh reinitialises
the cells whose closest point is on a rim: rim_cells). Shell cells take the side found one cell
further along the direction from their closest point. (trimesh's own signed_distance, with
rtree, is slower on the band's cells and needs consistent orientation: docs/surface.md,
measured by benchmarks/surface_accuracy.py, section 5.)
"""

from __future__ import annotations

import contextlib
import os
import time
import warnings

import numpy as np

from ..errors import InputError
from ..imagedata import positive
from ..runtime import get_runtime
from .winding import WindingNumbers

# The kernels/ files this module's kernel lookups name (tests/core/test_kernel_names.py checks).
KERNEL_FILES = ("surface/mesh.cl",)


def load_mesh(mesh):
    """A trimesh.Trimesh from a Trimesh, a Scene or any file trimesh can load."""
    import trimesh

    if isinstance(mesh, (str, bytes)) or hasattr(mesh, "__fspath__"):
        try:
            mesh = trimesh.load(mesh, force="mesh")
        except Exception as exc:  # noqa: BLE001  (trimesh raises many kinds for unreadable files)
            raise InputError(f"could not read a mesh from {mesh!s}: {exc}") from None
    if isinstance(mesh, trimesh.Scene):
        mesh = mesh.dump(concatenate=True)
    if not isinstance(mesh, trimesh.Trimesh):
        raise InputError(f"expected a trimesh.Trimesh or a mesh file, got {type(mesh).__name__}")
    if len(mesh.faces) == 0:
        raise InputError("the mesh has no triangles")
    if not np.all(np.isfinite(mesh.vertices)):
        raise InputError("the mesh has NaN or infinite vertex coordinates")
    if not mesh.is_watertight:
        warnings.warn(
            "the mesh is not watertight; its holes are closed by the winding number, along the "
            "sheet where it crosses 1/2 (a smooth patch, not a reconstruction of what is "
            "missing: repair the mesh if the holes' shape matters)",
            stacklevel=3,
        )
    return mesh


def grid_for_mesh(mesh, spacing=None, resolution=128, padding=8):
    """(origin, spacing, shape) of a grid enclosing the mesh with `padding` cells a side;
    spacing defaults to the longest side of the bounding box / resolution."""
    lo, hi = mesh.bounds
    extent = float((hi - lo).max())
    if extent <= 0:
        raise InputError("the mesh is flat or a single point; it encloses no volume")
    h = positive("spacing", extent / int(resolution) if spacing is None else spacing)
    origin = lo - padding * h
    n = np.ceil((hi - lo) / h).astype(int) + 2 * padding + 1
    return origin, h, (int(n[2]), int(n[1]), int(n[0]))


def _surface_samples(mesh, step):
    """Points on every triangle at most about `step` apart, with their triangle index."""
    tri = np.asarray(mesh.triangles, dtype=np.float64)
    edges = np.linalg.norm(tri[:, [1, 2, 0]] - tri, axis=2).max(axis=1)
    levels = np.clip(np.ceil(edges / step).astype(int), 1, 64)
    points, owners = [tri.mean(axis=1)], [np.arange(len(tri))]
    for n in np.unique(levels):
        faces = np.flatnonzero(levels == n)
        i, j = np.meshgrid(np.arange(n + 1), np.arange(n + 1), indexing="ij")
        keep = i + j <= n
        a, b = i[keep] / n, j[keep] / n
        w = np.stack([1 - a - b, a, b], axis=1)  # barycentric grid, vertices included
        pts = np.einsum("kv,fvd->fkd", w, tri[faces])
        points.append(pts.reshape(-1, 3))
        owners.append(np.repeat(faces, len(w)))
    return np.concatenate(points), np.concatenate(owners)


def mesh_to_sdf(mesh, origin, spacing, shape, band_cells, passes=3, device=None, stats=None):
    """Signed distance (nz, ny, nx), negative inside, exact within band_cells of the mesh
    (up to picking the nearest triangle through the nearest surface-crossing cell).

    Returns (psi, closest_face, closest_point): closest_face is a volume, -1 off the band;
    closest_point has one row per band cell (where closest_face >= 0), in flat index order.
    Only the band's cells get per-cell closest points: a volume of them would take 24 bytes
    a cell. The sign: the module's docstring; the winding numbers add a
    volume of labels and a few of booleans, and hold w for the cells they decide only.
    stats, a dict, receives the components of the flood fill, how many leaked, how many
    points had their winding number evaluated and the seconds the sign's check took."""
    from scipy import ndimage

    h = float(spacing)
    nz, ny, nx = shape
    total = nz * ny * nx
    cap = band_cells * h
    # cells the surface passes through, each with two of the triangles crossing it
    points, owners = _surface_samples(mesh, 0.5 * h)
    ijk = np.clip(np.rint((points - origin) / h).astype(int), 0, np.array([nx, ny, nz]) - 1)
    flat = np.ravel_multi_index((ijk[:, 2], ijk[:, 1], ijk[:, 0]), shape)
    first = np.full(total, -1, dtype=np.int32)
    first[flat[::-1]] = owners[::-1]
    crossed = (first >= 0).reshape(shape)
    # Euclidean distance transform: every cell's nearest crossed cell (in cells)
    cell_dist, nearest = ndimage.distance_transform_edt(~crossed, return_indices=True)
    idx = np.flatnonzero(cell_dist.ravel() <= band_cells + 1.5)
    src = np.ravel_multi_index(tuple(a.ravel()[idx] for a in nearest), shape)
    del cell_dist, nearest, crossed
    face0 = np.full(total, -1, dtype=np.int32)
    face0[idx] = first[src]
    # exact nearest triangles: propagate candidates between neighbouring cells on the device
    face, dist, cpt = _refine_on_device(mesh, origin, h, shape, idx, face0, passes, device)
    udist = np.full(total, np.inf)
    udist[idx] = dist
    udist = udist.reshape(shape)
    # sign by flood fill from the border through cells outside the half-cell shell, checked
    # (and where it leaked through a hole, replaced) by the winding number
    shell = udist <= 0.5 * h * (1 + 1e-6)
    labels, nlabels = ndimage.label(~shell)
    border = np.unique(
        np.concatenate(
            [
                labels[0].ravel(),
                labels[-1].ravel(),
                labels[:, 0].ravel(),
                labels[:, -1].ravel(),
                labels[:, :, 0].ravel(),
                labels[:, :, -1].ravel(),
            ]
        )
    )
    inside, outside = _sign_by_winding(
        mesh,
        labels,
        nlabels,
        border[border > 0],
        idx,
        origin,
        h,
        band_cells,
        device,
        stats,
        face=face,
        closest=cpt,
    )
    del labels
    sign = np.where(inside, -1.0, 1.0)
    # shell cells: look one and a half cells further from the surface along x - cp
    sidx = np.flatnonzero(shell.ravel())
    if sidx.size:
        shell_cp = cpt[np.searchsorted(idx, sidx)]  # shell cells are band cells
        kz, rem = np.divmod(sidx, ny * nx)
        ky, kx = np.divmod(rem, nx)
        centres_s = origin + h * np.stack([kx, ky, kz], axis=1)
        direction = centres_s - shell_cp
        length = np.linalg.norm(direction, axis=1)
        direction /= np.where(length > 0, length, 1)[:, None]
        votes = np.zeros(sidx.size)
        for step in (1.0, 1.5, 2.0):
            probe = shell_cp + step * h * direction
            ijk = np.rint((probe - origin) / h).astype(int)
            ijk = np.clip(ijk, 0, np.array([nx, ny, nz]) - 1)
            flat = np.ravel_multi_index((ijk[:, 2], ijk[:, 1], ijk[:, 0]), shape)
            votes += np.where(inside.ravel()[flat], -1, np.where(outside.ravel()[flat], 1, 0))
        # on-surface cells (length 0) have no direction: their |psi| is ~0 anyway
        sign.ravel()[sidx] = np.where(votes < 0, -1.0, 1.0)
    psi = sign * np.minimum(udist, cap)
    return psi, face.reshape(shape), cpt


def rim_cells(mesh, face, closest_point, spacing) -> np.ndarray:
    """Flat indices of the band cells whose closest mesh point lies on a boundary edge (the
    rim of a hole): where mesh_to_sdf closed a hole, their |psi| is the distance to the rim,
    not to the surface that closes it. face and closest_point as mesh_to_sdf returns them."""
    flat_face = face.reshape(-1)
    cells = np.flatnonzero(flat_face >= 0)
    counts = np.bincount(np.asarray(mesh.edges_unique_inverse), minlength=len(mesh.edges_unique))
    on_boundary = (counts == 1)[np.asarray(mesh.faces_unique_edges)]  # (faces, 3)
    near = on_boundary[flat_face[cells]].any(axis=1)
    if not near.any():
        return np.zeros(0, dtype=np.int64)
    rim_faces = flat_face[cells[near]]
    edges = np.asarray(mesh.edges_unique)[np.asarray(mesh.faces_unique_edges)[rim_faces]]
    vertices = np.asarray(mesh.vertices, dtype=np.float64)
    a, b = vertices[edges[..., 0]], vertices[edges[..., 1]]  # (n, 3 edges, 3)
    p = closest_point[near][:, None, :]
    t = np.clip(
        ((p - a) * (b - a)).sum(axis=2) / np.maximum(((b - a) ** 2).sum(axis=2), 1e-300), 0, 1
    )
    gap = np.linalg.norm(a + t[..., None] * (b - a) - p, axis=2)
    gap = np.where(on_boundary[rim_faces], gap, np.inf).min(axis=1)
    return cells[near][gap < 1e-3 * spacing]


def _oriented_triangles(mesh) -> np.ndarray:
    """The mesh's triangles (faces, 3, 3), consistently wound: trimesh.repair.fix_winding on
    a copy when they are not (the caller's mesh is left as it is)."""
    import trimesh

    if mesh.is_winding_consistent:
        return np.asarray(mesh.triangles, dtype=np.float64)
    copy = mesh.copy()
    trimesh.repair.fix_winding(copy)
    return np.asarray(copy.triangles, dtype=np.float64)


def _face_components(mesh) -> np.ndarray:
    """Connected part (by shared edges) of every face."""
    import trimesh

    return trimesh.graph.connected_component_labels(mesh.face_adjacency, node_count=len(mesh.faces))


def _cells_of(labels, box, label, count, rng) -> np.ndarray:
    """Up to `count` random flat indices of cells labelled `label` within the slices box."""
    shape = labels.shape
    lo = np.array([b.start for b in box])
    ext = np.array([b.stop - b.start for b in box])
    found = np.zeros(0, dtype=np.int64)
    for _ in range(4):  # random draws in the bounding box, kept where the label matches
        pos = lo + (rng.random((4 * count, 3)) * ext).astype(np.int64)
        flat = np.ravel_multi_index(tuple(pos.T), shape)
        found = np.unique(np.concatenate([found, flat[labels.reshape(-1)[flat] == label]]))
        if found.size >= count:
            return rng.choice(found, count, replace=False)
    local = np.argwhere(labels[box] == label) + lo  # a sparse component: list its cells
    flat = np.ravel_multi_index(tuple(local.T), shape)
    return rng.choice(flat, min(count, flat.size), replace=False)


def _node_starts(n, step):
    """First cell of each lattice node's block along an axis of n cells (cell i belongs to
    node floor(i / step + 1/2)), and the node of every cell."""
    nodes = int(np.floor((n - 1) / step + 0.5)) + 1
    starts = np.maximum(np.ceil(np.arange(nodes) * step - step / 2), 0).astype(np.int64)
    return starts, np.floor(np.arange(n) / step + 0.5).astype(np.int64)


def _face_sides(triangles, components, face, closest, centres, side_of, samples=64):
    """Inside (True) / outside for band cells whose closest point lies inside its triangle
    (not on an edge or a corner): the side of that triangle's plane, which needs no winding
    number. Returns (decided mask, inside). The oriented copy's faces point all outward or
    all inward per connected part, so each part's orientation is found once, by the winding
    number (side_of) at up to `samples` of its decided cells."""
    tri = triangles[face]
    a, b, c = tri[:, 0], tri[:, 1], tri[:, 2]
    normal = np.cross(b - a, c - a)
    # barycentric coordinates of the closest points (they lie in the triangle's plane)
    area2 = np.einsum("ij,ij->i", normal, normal)
    bary = np.stack(
        [
            np.einsum("ij,ij->i", np.cross(c - b, closest - b), normal),
            np.einsum("ij,ij->i", np.cross(a - c, closest - c), normal),
        ],
        axis=1,
    )
    bary /= np.maximum(area2, 1e-300)[:, None]
    interior = (bary.min(axis=1) > 1e-3) & (1 - bary.sum(axis=1) > 1e-3)
    offset = np.einsum("ij,ij->i", centres - closest, normal)
    decided = interior & (np.abs(offset) > 1e-6 * np.sqrt(area2))
    below = offset < 0  # behind the face: inside if the face points outward
    part = components[face]
    nparts = part.max() + 1 if part.size else 1
    # up to `samples` decided cells of every part, all in one winding-number evaluation
    rng = np.random.default_rng(1)
    cells = np.flatnonzero(decided)
    cells = cells[np.argsort(rng.random(cells.size))]  # shuffled, then grouped by part
    cells = cells[np.argsort(part[cells], kind="stable")]
    first = np.searchsorted(part[cells], np.arange(nparts))
    pick = cells[np.arange(cells.size) - first[part[cells]] < samples]
    agree = np.bincount(part[pick], weights=side_of(pick) == below[pick], minlength=nparts)
    outward = agree >= 0.5 * np.bincount(part[pick], minlength=nparts)
    return decided, np.where(outward[part], below, ~below)


class _Winding:
    """The winding number at cells of the grid (|w| > 1/2 is inside, so an inside-out mesh
    works too), counting the points it is evaluated at in `info`."""

    def __init__(self, wn: WindingNumbers, shape: tuple, info: dict):
        self.wn, self.shape, self.info = wn, shape, info

    def xyz(self, cells: np.ndarray) -> np.ndarray:
        """Grid coordinates (x, y, z) of flat cell indices."""
        z, rem = np.divmod(cells, self.shape[1] * self.shape[2])
        y, x = np.divmod(rem, self.shape[2])
        return np.stack([x, y, z], axis=1).astype(np.float64)

    def inside(self, cells: np.ndarray) -> np.ndarray:
        """|w| > 1/2 at flat cell indices."""
        self.info["winding_points"] += len(cells)
        return np.abs(self.wn(self.xyz(cells))) > 0.5

    def inside_at(self, points: np.ndarray) -> np.ndarray:
        """|w| > 1/2 at grid points (x, y, z)."""
        self.info["winding_points"] += len(points)
        return np.abs(self.wn(points)) > 0.5


def _sign_by_winding(
    mesh,
    labels,
    nlabels,
    border,
    idx,
    origin,
    h,
    band_cells,
    device,
    stats,
    samples=128,
    face=None,
    closest=None,
):
    """(inside, outside) volumes for the cells off the shell (labels > 0, the components of
    the flood fill; border: the labels touching the box's border).

    The flood fill says border components are outside and the others inside. Up to
    2 * samples cells of every component (random ones of its bounding box and of its band
    cells) have their winding number evaluated: a component whose samples all agree takes
    that side; a border component with samples inside, or one whose samples disagree, has
    leaked through a hole, and each of its cells is decided by |w| > 1/2: band cells each at
    their own centre, cells beyond the band at the nearest node of a lattice of spacing
    min(4, band_cells) cells. Those lie farther than band_cells from the mesh and their node
    within 0.87 * spacing < band_cells, so the segment between them meets no triangle: w is
    smooth (harmonic) along it and the node's side is the cell's, except within the
    lattice's reach of the w = 1/2 sheet spanning a hole, where no side is right anyway."""
    start = time.perf_counter()
    shape = labels.shape
    is_border = np.zeros(nlabels + 1, dtype=bool)
    is_border[border] = True
    info = {"components": int(nlabels), "leaked": 0, "winding_points": 0}
    if nlabels == 0:
        return np.zeros(shape, dtype=bool), np.zeros(shape, dtype=bool)
    oriented = _oriented_triangles(mesh)
    winding = _Winding(WindingNumbers((oriented - origin) / h, device=device), shape, info)
    band_label = labels.reshape(-1)[idx]
    votes_in, votes = _component_votes(labels, nlabels, idx, band_label, samples, winding)
    some_in = votes_in > 0
    all_in = some_in & (votes_in == votes)
    leaked = (votes > 0) & ((is_border & some_in) | (some_in & ~all_in))
    # a component the flood fill calls inside with no sample inside (the cavity of a hollow
    # part, say) is outside
    inside_label = ~is_border & ~leaked & all_in
    lut = np.where(inside_label, 1, 0).astype(np.int8)
    lut[leaked] = 2
    lut[0] = 3
    klass = lut[labels]  # 0 outside, 1 inside, 2 leaked, 3 shell
    inside = klass == 1
    outside = klass == 0
    info["leaked"] = int(leaked.sum())
    if leaked.any():
        # band cells of leaked components: by the side of their closest triangle's plane
        # where their closest point lies inside it (most of them), else by their own
        # winding number (closest points on edges, corners and the holes' rims)
        in_leaked = leaked[band_label]
        cells = idx[in_leaked]
        cells_in = np.zeros(cells.size, dtype=bool)
        todo = np.ones(cells.size, dtype=bool)
        if face is not None and closest is not None and cells.size:
            decided, local_in = _face_sides(
                oriented,
                _face_components(mesh),
                face.reshape(-1)[cells],
                closest[np.flatnonzero(in_leaked)],  # rows of closest (idx order)
                origin + h * winding.xyz(cells),
                lambda k: winding.inside(cells[k]),
            )
            cells_in[decided] = local_in[decided]
            todo = ~decided
            info["decided_by_faces"] = int(decided.sum())
        cells_in[todo] = winding.inside(cells[todo])
        inside.reshape(-1)[cells] = cells_in
        outside.reshape(-1)[cells] = ~cells_in
        # cells beyond the band: the nearest node of a coarse lattice
        off_band = klass.reshape(-1) == 2
        off_band[idx] = False
        off_band = off_band.reshape(shape)
        up = _lattice_sides(off_band, band_cells, winding)
        inside[off_band] = up[off_band]
        outside[off_band] = ~up[off_band]
    info["seconds"] = time.perf_counter() - start
    if stats is not None:
        stats.update(info)
    return inside, outside


def _component_votes(labels, nlabels, idx, band_label, samples, winding):
    """(samples inside, samples) per label: random cells of each component's bounding box
    and of its band cells (idx, labelled band_label), up to `samples` of each."""
    from scipy import ndimage

    rng = np.random.default_rng(0)
    by_label = np.argsort(band_label, kind="stable")
    bounds = np.searchsorted(band_label[by_label], np.arange(nlabels + 2))
    boxes = ndimage.find_objects(labels)
    picks, owner = [], []
    for c in range(1, nlabels + 1):
        if boxes[c - 1] is None:
            continue
        band_c = idx[by_label[bounds[c] : bounds[c + 1]]]
        cells = _cells_of(labels, boxes[c - 1], c, samples, rng)
        if band_c.size:
            cells = np.union1d(cells, rng.choice(band_c, min(samples, band_c.size), replace=False))
        picks.append(cells)
        owner.append(np.full(cells.size, c))
    picks, owner = np.concatenate(picks), np.concatenate(owner)
    votes_in = np.bincount(owner, weights=winding.inside(picks), minlength=nlabels + 1)
    return votes_in, np.bincount(owner, minlength=nlabels + 1)


def _lattice_sides(off_band, band_cells, winding) -> np.ndarray:
    """Inside or not for every cell, from the nearest node of a lattice of spacing
    min(4, band_cells) cells; only the nodes next to `off_band` cells are evaluated."""
    step = int(np.clip(np.floor(band_cells), 1, 4))
    (sz, mz), (sy, my), (sx, mx) = (_node_starts(n, step) for n in off_band.shape)
    needed = np.logical_or.reduceat(off_band, sz, axis=0)
    needed = np.logical_or.reduceat(needed, sy, axis=1)
    needed = np.logical_or.reduceat(needed, sx, axis=2)
    nodes = np.argwhere(needed)
    node_in = np.zeros(needed.shape, dtype=bool)
    if len(nodes):
        node_in[tuple(nodes.T)] = winding.inside_at((step * nodes[:, ::-1]).astype(np.float64))
    return node_in[np.ix_(mz, my, mx)]


def _refine_on_device(mesh, origin, h, shape, idx, face0, passes, device=None):
    """`passes` rounds of mesh_refine over the cells idx; returns (face volume, distances,
    closest points) with distances and points in world units."""
    import pyopencl.array as cla

    rt = get_runtime(device)
    q = rt.queue
    nz, ny, nx = shape
    tri = ((np.asarray(mesh.triangles, dtype=np.float64) - origin) / h).astype(np.float32)
    tri_dev = cla.to_device(q, np.ascontiguousarray(tri.reshape(-1)))
    cells = cla.to_device(q, idx.astype(np.int32))
    faces = [cla.to_device(q, face0), cla.to_device(q, face0)]
    dist = cla.empty(q, max(idx.size, 1), np.float32)
    cpt = cla.empty(q, 3 * max(idx.size, 1), np.float32)
    nbr_dev = cla.to_device(q, _edge_neighbours(mesh))
    kernel = rt.kernel("surface/mesh.cl", "mesh_refine")
    for _ in range(max(1, int(passes))):
        kernel(
            q,
            *rt.items(idx.size),
            cells.data,
            np.int32(idx.size),
            faces[0].data,
            faces[1].data,
            dist.data,
            cpt.data,
            tri_dev.data,
            nbr_dev.data,
            np.int32(nx),
            np.int32(ny),
            np.int32(nz),
        )
        faces.reverse()
    d = dist.get()[: idx.size].astype(np.float64) * h
    cp = origin + h * cpt.get()[: 3 * idx.size].reshape(-1, 3).astype(np.float64)
    return faces[0].get(), d, cp


def _edge_neighbours(mesh) -> np.ndarray:
    """(faces, 3) int32: up to three faces sharing an edge with each face, -1 padded."""
    table = np.full((len(mesh.faces), 3), -1, dtype=np.int32)
    pairs = np.asarray(mesh.face_adjacency, dtype=np.int64).reshape(-1, 2)
    both = np.concatenate([pairs, pairs[:, ::-1]])
    both = both[np.argsort(both[:, 0], kind="stable")]
    if len(both):
        start = np.searchsorted(both[:, 0], both[:, 0], side="left")
        slot = np.arange(len(both)) - start
        keep = slot < 3
        table[both[keep, 0], slot[keep]] = both[keep, 1]
    return table.reshape(-1)


@contextlib.contextmanager
def encloses_volume(mesh):
    """Say why a mesh gives psi without a zero level set (psi, from the winding number,
    never changes sign on the grid): an open sheet has no inside, and a closed shape
    thinner than the spacing has no grid cell inside."""
    try:
        yield
    except InputError as exc:
        if "no zero level set" not in str(exc):
            raise

        name = f"the mesh {mesh}" if isinstance(mesh, (str, os.PathLike)) else "the mesh"
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # the watertightness warning was already given
            closed = load_mesh(mesh).is_watertight
        if closed:
            raise InputError(
                f"no grid cell lies inside {name}: it is thinner than the grid's "
                "spacing; use a finer grid (a larger resolution, --resolution "
                "on the command line)"
            ) from None
        raise InputError(
            f"{name} encloses no volume (an open sheet, not a closed surface), "
            "so it has no inside and outside to work between; give a closed "
            "(watertight) mesh, or close its holes first"
        ) from None

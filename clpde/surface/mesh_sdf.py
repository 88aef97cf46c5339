"""Triangle mesh -> signed distance volume, fast enough for 128^3-256^3 grids.

Magnitude: the unsigned distance to the mesh in the band. Points sampled every half cell on
the triangles mark the cells the surface crosses (keeping two crossing triangles per cell);
a Euclidean distance transform gives every cell its nearest crossed cell, and the exact
point-triangle distance to that cell's triangles is taken. Cells beyond the band get the
band's cap, with their sign. (A k-d tree over the samples was measured 5-10x slower.)

Sign: orientation-free, so flipped faces do not matter and holes smaller than a cell are
sealed: the cells closer than half a cell to the mesh form a shell that no 6-connected path
crosses; a flood fill from the box's border through the other cells finds the outside;
every other cell is inside. Shell cells take the side found one cell further along the
direction from their closest point. (trimesh's own signed_distance, with rtree, took 6-50x
longer on the band's cells at 64-256 cells across, and needs consistent orientation:
benchmarks/surface_accuracy.py, section 5.)
"""

from __future__ import annotations

import warnings

import numpy as np

from ..imagedata import InputError


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
            "the mesh is not watertight; holes smaller than a grid cell are sealed, larger ones "
            "may let the outside leak in (check the result, or repair the mesh first)",
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
    h = extent / int(resolution) if spacing is None else float(spacing)
    if not np.isfinite(h) or h <= 0:
        raise InputError(f"spacing must be a positive number, not {spacing!r}")
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


def mesh_to_sdf(mesh, origin, spacing, shape, band_cells, passes=3, device=None):
    """Signed distance (nz, ny, nx), negative inside, exact within band_cells of the mesh
    (up to picking the nearest triangle through the nearest surface-crossing cell).

    Returns (psi, closest_face, closest_point): closest_face is a volume, -1 off the band;
    closest_point has one row per band cell (where closest_face >= 0), in flat index order.
    Only the band's cells get per-cell closest points: a volume of them would take 24 bytes
    a cell (0.5 GB at 275^3)."""
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
    # sign by flood fill from the border through cells outside the half-cell shell
    shell = udist <= 0.5 * h * (1 + 1e-6)
    labels, _ = ndimage.label(~shell)
    border = np.unique(np.concatenate([
        labels[0].ravel(), labels[-1].ravel(), labels[:, 0].ravel(), labels[:, -1].ravel(),
        labels[:, :, 0].ravel(), labels[:, :, -1].ravel(),
    ]))
    outside = np.isin(labels, border[border > 0])
    inside = ~outside & ~shell
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


def _refine_on_device(mesh, origin, h, shape, idx, face0, passes, device=None):
    """`passes` rounds of mesh_refine over the cells idx; returns (face volume, distances,
    closest points) with distances and points in world units."""
    import pyopencl.array as cla

    from ..runtime import get_runtime

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
    kernel = rt.kernel("surface.cl", "mesh_refine")
    for _ in range(max(1, int(passes))):
        kernel(q, (idx.size,), None, cells.data, np.int32(idx.size), faces[0].data,
               faces[1].data, dist.data, cpt.data, tri_dev.data, nbr_dev.data, np.int32(nx), np.int32(ny),
               np.int32(nz))
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

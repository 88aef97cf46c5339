"""Generalized winding numbers of triangle meshes on the device (kernels/surface/winding.cl): about
1 inside a closed mesh, 0 outside, near 1/2 across a hole. mesh_sdf uses them to give
meshes with holes the right sign."""

from __future__ import annotations

import numpy as np

from ..errors import InputError
from ..runtime import get_runtime

# The kernels/ files this module's kernel lookups name (tests/core/test_kernel_names.py checks).
KERNEL_FILES = ("surface/winding.cl",)


def _morton_order(points: np.ndarray) -> np.ndarray:
    """Indices sorting points (n, 3) along a Morton (Z-order) curve, 10 bits an axis."""
    lo = points.min(axis=0)
    extent = max(float((points.max(axis=0) - lo).max()), 1e-300)
    q = np.clip(((points - lo) / extent * 1023).astype(np.int64), 0, 1023)
    code = np.zeros(len(points), dtype=np.int64)
    for bit in range(10):
        for axis in range(3):
            code |= ((q[:, axis] >> bit) & 1) << (3 * bit + axis)
    return np.argsort(code, kind="stable")


class WindingNumbers:
    """Generalized winding numbers w(p) of a triangle mesh, evaluated on the device
    (kernels/surface/winding.cl): about 1 inside, 0 outside, near 1/2 across a hole.

    triangles: (faces, 3, 3) in the units the points will come in (grid cells relative to the
    grid origin for mesh_to_sdf). The triangles are sorted along a Morton curve into clusters
    of `cluster` consecutive ones; `beta` sets the far field: a box of points (a tile of
    `tile` units) takes a cluster's second-order expansion where the box is farther than
    beta * (cluster radius) from the cluster's centre, the exact triangle sum otherwise.
    beta = 2 keeps the expansion's error far below what deciding a side needs (|w| is
    compared with 1/2; docs/surface.md has the errors and the cost of a larger beta), and
    tests/surface/test_surface_mesh.py holds it to 0.05."""

    def __init__(self, triangles, cluster=64, device=None):
        import pyopencl.array as cla

        tri = np.asarray(triangles, dtype=np.float64).reshape(-1, 3, 3)
        if len(tri) == 0:
            raise InputError("the mesh has no triangles")
        self.rt = get_runtime(device)
        q = self.rt.queue
        tri = tri[_morton_order(tri.mean(axis=1))]
        nf = len(tri)
        starts = np.arange(0, nf, int(cluster))
        area_vec = 0.5 * np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
        area = np.linalg.norm(area_vec, axis=1)
        centroid = tri.mean(axis=1)
        weight = np.add.reduceat(area, starts)
        count = np.diff(np.append(starts, nf))
        plain = np.add.reduceat(centroid, starts) / count[:, None]
        weighted = (
            np.add.reduceat(centroid * area[:, None], starts)
            / np.where(weight > 0, weight, 1)[:, None]
        )
        centre = np.where((weight > 0)[:, None], weighted, plain)
        owner = np.repeat(np.arange(len(starts)), count)
        reach = np.linalg.norm(tri - centre[owner][:, None, :], axis=2).max(axis=1)
        self.radius = np.maximum.reduceat(reach, starts)
        self.centre = centre
        moment = np.einsum("fi,fj->fij", area_vec, centroid - centre[owner]).reshape(nf, 9)
        clu = np.concatenate(
            [centre, np.add.reduceat(area_vec, starts), np.add.reduceat(moment, starts)], axis=1
        )
        self.nclusters = len(starts)
        self.triangles = tri
        self._cl_start = cla.to_device(q, np.append(starts, nf).astype(np.int32))
        self._clu = cla.to_device(q, np.ascontiguousarray(clu, dtype=np.float32).reshape(-1))
        self._tri = cla.to_device(q, np.ascontiguousarray(tri, dtype=np.float32).reshape(-1))
        self._chunk = 64 if self.rt.is_cpu else 1
        self._kernel = self.rt.kernel("surface/winding.cl", "winding_number", CHUNK=self._chunk)

    def __call__(self, points, exact=False, beta=2.0, tile=8.0) -> np.ndarray:
        """w at points (n, 3), float64 (computed in float32). exact=True sums every triangle."""
        import pyopencl.array as cla

        pts = np.asarray(points, dtype=np.float64).reshape(-1, 3)
        n = len(pts)
        if n == 0:
            return np.zeros(0)
        q = self.rt.queue
        # points grouped into tiles (boxes of `tile` units), tiles into chunks of work-items
        key3 = np.floor(pts / float(tile)).astype(np.int64)
        key3 -= key3.min(axis=0)
        span = key3.max(axis=0) + 1
        key = (key3[:, 2] * span[1] + key3[:, 1]) * span[0] + key3[:, 0]
        order = np.argsort(key, kind="stable")
        key = key[order]
        sorted_pts = pts[order]
        tile_start = np.flatnonzero(np.r_[True, key[1:] != key[:-1]])
        tile_size = np.diff(np.append(tile_start, n))
        lo = np.minimum.reduceat(sorted_pts, tile_start)
        hi = np.maximum.reduceat(sorted_pts, tile_start)
        ntiles = len(tile_start)
        # near (exact) and far (expansion) clusters of every tile, in blocks of tiles
        near_rows, near_cols, far_rows, far_cols = [], [], [], []
        block = max(1, 4_000_000 // self.nclusters)
        for t0 in range(0, ntiles, block):
            t1 = min(t0 + block, ntiles)
            if exact:
                near = np.ones((t1 - t0, self.nclusters), dtype=bool)
            else:
                gap = np.maximum(
                    np.maximum(lo[t0:t1, None, :] - self.centre[None], 0),
                    self.centre[None] - hi[t0:t1, None, :],
                )
                dist = np.linalg.norm(np.maximum(gap, 0), axis=2)
                near = dist <= float(beta) * self.radius[None]
            r, c = np.nonzero(near)
            near_rows.append(r + t0)
            near_cols.append(c)
            r, c = np.nonzero(~near)
            far_rows.append(r + t0)
            far_cols.append(c)
        near_rows, near_cols = np.concatenate(near_rows), np.concatenate(near_cols)
        far_rows, far_cols = np.concatenate(far_rows), np.concatenate(far_cols)
        near_off = np.searchsorted(near_rows, np.arange(ntiles + 1)).astype(np.int32)
        far_off = np.searchsorted(far_rows, np.arange(ntiles + 1)).astype(np.int32)
        self.last_near_fraction = len(near_rows) / max(ntiles * self.nclusters, 1)
        # chunks of at most CHUNK points of one tile
        per_tile = -(-tile_size // self._chunk)
        chunk_tile = np.repeat(np.arange(ntiles), per_tile)
        first_chunk = np.cumsum(per_tile) - per_tile
        chunk_start = tile_start[chunk_tile] + self._chunk * (
            np.arange(len(chunk_tile)) - first_chunk[chunk_tile]
        )
        chunk_end = np.minimum(chunk_start + self._chunk, (tile_start + tile_size)[chunk_tile])

        def dev(a, dtype=np.int32):
            a = np.ascontiguousarray(a, dtype=dtype)
            return cla.to_device(q, a if a.size else np.zeros(1, dtype)).data

        out = cla.empty(q, n, np.float32)
        nchunks = len(chunk_tile)
        self._kernel(
            q,
            *self.rt.items(nchunks),
            dev(sorted_pts.reshape(-1), np.float32),
            dev(chunk_start),
            dev(chunk_end),
            dev(chunk_tile),
            np.int32(nchunks),
            dev(near_off),
            dev(near_cols),
            dev(far_off),
            dev(far_cols),
            self._cl_start.data,
            self._clu.data,
            self._tri.data,
            out.data,
        )
        w = np.empty(n)
        w[order] = out.get()
        return w


def winding_number(mesh, points, *, exact=False, beta=2.0, device=None) -> np.ndarray:
    """Generalized winding number of `mesh` (a trimesh.Trimesh, used as it is: orient it
    first for a meaningful sign) at world points (n, 3); see WindingNumbers."""
    tri = np.asarray(mesh.triangles, dtype=np.float64)
    lo, hi = tri.reshape(-1, 3).min(axis=0), tri.reshape(-1, 3).max(axis=0)
    scale = max(float((hi - lo).max()), 1e-300) / 128  # work in units of 1/128 of the box
    wn = WindingNumbers((tri - lo) / scale, device=device)
    return wn((np.asarray(points, dtype=np.float64) - lo) / scale, exact=exact, beta=beta, tile=8.0)

"""Meshes for region tracking: the starting surface, auxiliary functions from vertex masks,
and triangles split along the zero of the auxiliary functions (sub-triangle boundaries).

Everything here runs on the host: it prepares the inputs and reads out saved frames.
"""

from __future__ import annotations

import numpy as np

from ..errors import InputError

# Region colours: the thesis paints tracked regions yellow; further labels follow.
PALETTE = np.array(
    [
        [0.98, 0.85, 0.15],
        [0.85, 0.25, 0.2],
        [0.2, 0.65, 0.35],
        [0.25, 0.45, 0.85],
        [0.75, 0.4, 0.8],
        [0.95, 0.55, 0.15],
        [0.3, 0.75, 0.8],
        [0.6, 0.45, 0.3],
    ]
)
BACKGROUND = np.array([0.62, 0.66, 0.78])


def surface_mesh(phi, spacing=1.0, origin=(0.0, 0.0, 0.0)):
    """Marching cubes of phi = 0 as a trimesh.Trimesh in world (x, y, z) coordinates.

    This is the starting mesh whose vertices a region mask for track_region refers to."""
    import trimesh
    from skimage.measure import marching_cubes

    # marching_cubes works in float32: clip beyond its range rather than overflow to inf
    big = float(np.finfo(np.float32).max)
    phi = np.clip(np.asarray(phi, dtype=np.float64), -big, big)
    verts, faces, _, _ = marching_cubes(phi, 0.0, spacing=(float(spacing),) * 3)
    # marching_cubes gives (z, y, x); skimage orients faces for ascending values: flip them
    return trimesh.Trimesh(
        verts[:, ::-1] + np.asarray(origin, np.float64), faces[:, ::-1], process=False
    )


def functions_from_mask(phi, spacing, origin, mesh, masks) -> np.ndarray:
    """Auxiliary functions (one per mask) whose zero sets cut the surface along the masks'
    boundaries: Phi-hat(x) = +-distance from x's closest point on the surface to the
    boundary, negative where the closest mesh vertex is in the mask. Constant along the
    surface's normals, so Phi-hat = 0 meets the surface at right angles."""
    from scipy.spatial import cKDTree

    h = float(spacing)
    g = np.gradient(phi, h)
    norm = np.sqrt(g[0] ** 2 + g[1] ** 2 + g[2] ** 2)
    norm[norm == 0] = 1.0
    nz, ny, nx = phi.shape
    z, y, x = np.meshgrid(np.arange(nz), np.arange(ny), np.arange(nx), indexing="ij")
    d = phi / norm
    cp = np.stack(
        [origin[0] + h * x - d * g[2], origin[1] + h * y - d * g[1], origin[2] + h * z - d * g[0]],
        axis=-1,
    ).reshape(-1, 3)
    verts = np.asarray(mesh.vertices)
    _, nearest = cKDTree(verts).query(cp)
    edges = np.asarray(mesh.edges_unique)
    out = []
    for mask in masks:
        crossing = edges[mask[edges[:, 0]] != mask[edges[:, 1]]]
        if len(crossing) == 0:
            raise InputError(
                "a region mask has no boundary on the surface (it marks all or none "
                "of the vertices); mark some vertices, not all"
            )
        # boundary points: the crossing edges' midpoints and quarter points
        a, b = verts[crossing[:, 0]], verts[crossing[:, 1]]
        points = np.concatenate([a + f * (b - a) for f in (0.25, 0.5, 0.75)])
        dist, _ = cKDTree(points).query(cp)
        out.append(np.where(mask[nearest], -dist, dist).reshape(phi.shape))
    return np.stack(out)


def along_normals(phi, spacing, functions) -> np.ndarray:
    """Each function (L, nz, ny, nx) replaced by its value at the closest point of the surface
    phi = 0 (one Newton step, x - phi grad phi / |grad phi|^2, trilinear): unchanged on the
    surface, so the regions stay the same, and constant along the surface's normals.

    Why: a region function that meets the surface obliquely (a plane cutting a sphere) tilts
    across the narrow band, and the band's edges (faded speeds, values extended from inside)
    bend it; as the surface moves into those cells the tracked boundary drifts by about 0.1
    cell per cell moved, an error that does not shrink with the spacing. Meeting the surface
    at right angles, the function barely moves under the projected velocity."""
    from scipy.ndimage import map_coordinates

    h = float(spacing)
    g = np.gradient(np.asarray(phi, np.float64), h)
    step = phi / np.maximum(g[0] ** 2 + g[1] ** 2 + g[2] ** 2, 1e-12) / h  # cells per unit gradient
    nz, ny, nx = phi.shape
    z, y, x = np.meshgrid(np.arange(nz), np.arange(ny), np.arange(nx), indexing="ij", sparse=True)
    closest = [z - step * g[0], y - step * g[1], x - step * g[2]]
    return np.stack([map_coordinates(f, closest, order=1, mode="nearest") for f in functions])


def _split_once(verts, vals, faces, label):
    """Split the triangles whose corners straddle vals[:, label] = 0 along its linear zero."""
    inside = vals[faces, label] < 0
    count = inside.sum(axis=1)
    mixed = (count == 1) | (count == 2)
    if not mixed.any():
        return verts, vals, faces, np.zeros((0, 3))
    f, s = faces[mixed], inside[mixed]
    # roll each face (keeping its orientation) so that its lonely corner comes first
    lonely = np.where(count[mixed] == 1, np.argmax(s, axis=1), np.argmin(s, axis=1))
    f = np.take_along_axis(f, (lonely[:, None] + np.arange(3)) % 3, axis=1)
    a, b, c = f.T

    def cut(p, q):
        t = vals[p, label] / (vals[p, label] - vals[q, label])
        pos = verts[p] + t[:, None] * (verts[q] - verts[p])
        val = vals[p] + t[:, None] * (vals[q] - vals[p])
        val[:, label] = 0.0
        return pos, val

    pab, vab = cut(a, b)
    pac, vac = cut(a, c)
    n0, m = len(verts), len(f)
    ab, ac = n0 + np.arange(m), n0 + m + np.arange(m)
    new = np.concatenate(
        [np.stack([a, ab, ac], 1), np.stack([ab, b, c], 1), np.stack([ab, c, ac], 1)]
    )
    verts = np.concatenate([verts, pab, pac])
    vals = np.concatenate([vals, vab, vac])
    return verts, vals, np.concatenate([faces[~mixed], new]), pab


def split_regions(verts, vals, faces, partition=False):
    """Split a mesh along the zeros of its vertex values vals (n, L), one column per region.

    Returns (vertices, faces, face_labels, boundaries): vertices are shared only between
    faces of the same label (so vertex colours stay sharp along the cuts), face_labels the
    region each face lies in (the most negative function; -1 outside all, unless the
    regions partition the surface), boundaries the cut points on each region's boundary."""
    verts = np.asarray(verts, np.float64)
    vals = np.asarray(vals, np.float64).reshape(len(verts), -1)
    faces = np.asarray(faces, np.int64)
    boundaries = []
    for label in range(vals.shape[1]):
        verts, vals, faces, cut_points = _split_once(verts, vals, faces, label)
        boundaries.append(cut_points)
    centre = vals[faces].mean(axis=1)
    best = np.argmin(centre, axis=1)
    labels = best if partition else np.where(centre[np.arange(len(faces)), best] < 0, best, -1)
    # one vertex per (position, label): merge cut points made twice by neighbouring faces
    scale = 1e7 / max(np.ptp(verts, axis=0).max(), 1e-300)
    key = np.concatenate(
        [
            np.rint(verts[faces].reshape(-1, 3) * scale).astype(np.int64),
            np.repeat(labels, 3)[:, None],
        ],
        axis=1,
    )
    uniq, inverse = np.unique(key, axis=0, return_inverse=True)
    corner_pos = verts[faces].reshape(-1, 3)
    new_verts = np.zeros((len(uniq), 3))
    new_verts[inverse.reshape(-1)] = corner_pos
    return new_verts, inverse.reshape(-1, 3), labels, boundaries


def region_colours(labels, palette=None) -> np.ndarray:
    """RGB in [0, 1] per label: palette[label] (clpde's PALETTE by default), BACKGROUND for -1."""
    labels = np.asarray(labels)
    colours = PALETTE if palette is None else np.asarray(palette, np.float64).reshape(-1, 3)
    rgb = np.tile(BACKGROUND, (len(labels), 1))
    inside = labels >= 0
    rgb[inside] = colours[labels[inside] % len(colours)]
    return rgb


def _region_functions(phi, region, spacing, origin, mesh=None):
    """Phi-hat volumes (L, nz, ny, nx) from the `region` input (a vertex mask or labels refer
    to `mesh`, by default the starting mesh of phi), and whether they partition the surface
    (integer labels: every point lies in one region)."""
    region_arr = region if isinstance(region, (list, tuple)) else [region]
    arrays = [np.asarray(r) for r in region_arr]
    if all(a.shape == phi.shape for a in arrays):
        out = np.stack([a.astype(np.float64) for a in arrays])
        if not np.all(np.isfinite(out)):
            raise InputError("the region functions contain NaN or infinite values")
        return out, False
    if len(arrays) == 1 and arrays[0].ndim == 1:
        marks = arrays[0]
        if mesh is None:
            mesh = surface_mesh(phi, spacing, origin)
            if len(marks) != len(mesh.vertices):
                raise InputError(
                    f"a vertex mask needs one entry per vertex of the starting mesh "
                    f"(clpde.regions.surface_mesh(phi, spacing) has {len(mesh.vertices)}), got "
                    f"{len(marks)}; or pass mesh= the mesh whose vertices it marks"
                )
        else:
            mesh = _as_trimesh(mesh)
            if len(marks) != len(mesh.vertices):
                raise InputError(
                    f"a vertex mask needs one entry per vertex of mesh= "
                    f"({len(mesh.vertices)} vertices), got {len(marks)}"
                )
        if marks.dtype == bool:
            masks = [marks]
        elif np.issubdtype(marks.dtype, np.integer):
            values = np.unique(marks)
            if len(values) < 2:
                raise InputError("vertex labels need at least two different values")
            masks = [marks == v for v in values]
        else:
            raise InputError(
                f"a vertex mask must be bool (one region) or integer labels, not {marks.dtype}"
            )
        partition = marks.dtype != bool
        return functions_from_mask(phi, spacing, origin, mesh, masks), partition
    raise InputError(
        f"region must be a vertex mask/labels of the starting mesh (1-D), an implicit function of "
        f"phi's shape {phi.shape}, or a list of such functions; got shape(s) "
        f"{[a.shape for a in arrays]}"
    )


def _as_trimesh(mesh):
    """A trimesh.Trimesh from a Trimesh or a (vertices, faces) pair (not copied)."""
    import trimesh

    if isinstance(mesh, trimesh.Trimesh):
        return mesh
    try:
        vertices, faces = mesh
        return trimesh.Trimesh(np.asarray(vertices, np.float64), np.asarray(faces), process=False)
    except (TypeError, ValueError):
        raise InputError("mesh must be a trimesh.Trimesh or a (vertices, faces) pair") from None

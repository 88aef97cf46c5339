"""Inpainting on implicit surfaces (clpde.surface.inpaint): accuracy under refinement and
against a mesh peer, with times.

    python benchmarks/surface_inpaint.py [--json PATH] [--quick]

1. Exact harmonic functions with a cap removed, on a sphere (Re(w^2) + Re(w), w the
   stereographic coordinate from the north pole; cap z < -0.5) and a torus R = 1, r = 0.4
   (phi theta + phi / 2 in its isothermal coordinates; cap: points within 0.6 of the outer
   equator's (1.4, 0, 0)): the harmonic fill's largest error in the cap (over random points
   on the surface, sampled tricubically) at each spacing, against filling the cap with the
   mean of its rim (known cells within two cells of the hole), steps and time.
2. Meshes (trimesh icospheres and a torus, a marching-cubes mesh of clpde.data's
   double torus), a patch removed: clpde's fill at the vertices against the peer a mesh user
   would reach for, the harmonic fill with the mesh's cotangent Laplacian solved by
   scipy.sparse (spsolve); the data: the sphere's exact harmonic function on the icospheres,
   a smooth non-harmonic function elsewhere (there neither fill is the data: the difference
   between the two fills is what measures clpde). Times: clpde's surface (mesh to signed
   distance, bands) and fill separately; the peer's Laplacian and solve.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla
import trimesh

from clpde.surface import ImplicitSurface, surface_shape
from clpde.surface.inpainting import fill_mesh, inpaint

R, RT = 1.0, 0.4


def sphere_f(x, y, z):
    far = z >= 0.3
    d = np.where(far, 1.0, 1 - z)
    return np.where(far, 0.0, (x * x - y * y) / d**2 + x / d)


def torus_f(x, y, z):
    phi = np.arctan2(y, x)
    v = np.arctan2(z, np.sqrt(x * x + y * y) - R)
    c = np.sqrt(R * R - RT * RT)
    theta = 2 * RT / c * np.arctan(np.sqrt((R - RT) / (R + RT)) * np.tan(v / 2))
    return phi * theta + 0.5 * phi


def sphere_cap(p):
    return p[:, 2] + 0.5


def torus_cap(p):
    return np.linalg.norm(p - np.array([R + RT, 0, 0]), axis=1) - 0.6


def points(kind, n=20000, seed=1):
    rng = np.random.default_rng(seed)
    if kind == "sphere":
        p = rng.standard_normal((n, 3))
        p /= np.linalg.norm(p, axis=1)[:, None]
        return p[sphere_cap(p) < 0]
    phi, v = rng.uniform(-0.7, 0.7, n), rng.uniform(-np.pi, np.pi, n)
    p = np.stack(
        [(R + RT * np.cos(v)) * np.cos(phi), (R + RT * np.cos(v)) * np.sin(phi), RT * np.sin(v)],
        1,
    )
    return p[torus_cap(p) < 0]


def convergence(kind, spacings):
    rows = []
    for h in spacings:
        if kind == "sphere":
            s, f, cap = ImplicitSurface.sphere(1.0, spacing=h), sphere_f, sphere_cap
        else:
            s, f, cap = ImplicitSurface.torus(R, RT, spacing=h), torus_f, torus_cap
        u = s.band_field(f)
        cp = s.band_closest_points()
        hole = cap(cp) < 0
        inpaint(s, u, hole)  # warm: kernel builds
        t0 = time.perf_counter()
        out, info = inpaint(s, u, hole, return_info=True)
        seconds = time.perf_counter() - t0
        pts = points(kind)
        want = f(*pts.T)
        err = float(np.abs(s.sample(out, pts) - want).max())
        rim = float(np.abs(u[~hole & (cap(cp) < 2 * h)].mean() - want).max())
        rows.append(
            dict(
                kind=kind,
                h=h,
                hole_cells=info.hole_cells,
                steps=info.iterations,
                error=err,
                rim_mean_error=rim,
                seconds=seconds,
            )
        )
        print(json.dumps(rows[-1]), flush=True)
    return rows


def cotangent_fill(v, f, values, mask):
    rows, cols, vals = [], [], []
    for k in range(3):
        i, j, o = f[:, k], f[:, (k + 1) % 3], f[:, (k + 2) % 3]
        a, b = v[i] - v[o], v[j] - v[o]
        cot = (a * b).sum(1) / np.maximum(np.linalg.norm(np.cross(a, b), axis=1), 1e-300)
        rows += [i, j]
        cols += [j, i]
        vals += [0.5 * cot, 0.5 * cot]
    n = len(v)
    w = sp.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), (n, n))
    lap = (sp.diags(np.asarray(w.sum(1)).ravel()) - w).tocsr()
    h, k = np.flatnonzero(mask), np.flatnonzero(~mask)
    out = values.astype(np.float64).copy()
    out[h] = spla.spsolve(lap[h][:, h].tocsc(), -(lap[h][:, k] @ out[k]))
    return out


def smooth(x, y, z):
    return np.sin(2 * x) * np.cos(1.5 * y) + 0.5 * z


def meshes(quick):
    out = [
        ("icosphere(4)", trimesh.creation.icosphere(4), sphere_f, np.array([0, 0, -1.0]), 0.8),
        ("icosphere(5)", trimesh.creation.icosphere(5), sphere_f, np.array([0, 0, -1.0]), 0.8),
        (
            "torus 128x64",
            trimesh.creation.torus(1.0, 0.4, major_sections=128, minor_sections=64),
            smooth,
            np.array([1.4, 0, 0]),
            0.5,
        ),
    ]
    if not quick:
        dt = surface_shape("double-torus", 96).to_mesh()
        c = dt.vertices[np.argmax(dt.vertices[:, 0])]
        out.append(("double torus (marching cubes, 96)", dt, smooth, c, 0.4))
    return out


def mesh_rows(quick):
    rows = []
    for name, mesh, f, centre, radius in meshes(quick):
        v, faces = np.asarray(mesh.vertices), np.asarray(mesh.faces)
        values = f(*v.T)
        mask = np.linalg.norm(v - centre, axis=1) < radius
        t0 = time.perf_counter()
        peer = cotangent_fill(v, faces, values, mask)
        peer_s = time.perf_counter() - t0
        span = float(np.ptp(values[~mask]))
        for res in (64,) if quick else (64, 128):
            t0 = time.perf_counter()
            surf = ImplicitSurface.from_mesh(mesh, resolution=res)
            build_s = time.perf_counter() - t0
            got, info = fill_mesh(
                surf, values, mask, method="harmonic", tol=1e-5, max_iterations=None, progress=False
            )
            row = dict(
                mesh=name,
                vertices=len(v),
                missing=int(mask.sum()),
                resolution=res,
                clpde_vs_data=float(np.abs(got - values)[mask].max() / span),
                peer_vs_data=float(np.abs(peer - values)[mask].max() / span),
                clpde_vs_peer=float(np.abs(got - peer)[mask].max() / span),
                surface_s=build_s,
                fill_s=info.seconds,
                steps=info.iterations,
                peer_s=peer_s,
                exact=f is sphere_f,
            )
            rows.append(row)
            print(json.dumps(row), flush=True)
    return rows


def edge(h=0.05):
    """An edge (tanh across a great circle) through a cap of the sphere: harmonic against
    transport, mean and largest error in the cap."""
    s = ImplicitSurface.sphere(1.0, spacing=h)

    def f(x, y, z):
        return np.tanh((x + 0.3 * y) / 0.08)

    u = s.band_field(f)
    cp = s.band_closest_points()
    hole = np.linalg.norm(cp - np.array([0, 0, -1.0]), axis=1) < 0.6
    pts = points("sphere", 40000)
    pts = pts[np.linalg.norm(pts - np.array([0, 0, -1.0]), axis=1) < 0.55]
    want = f(*pts.T)
    rows = []
    for method in ("harmonic", "transport"):
        t0 = time.perf_counter()
        out, info = inpaint(s, u, hole, method=method, return_info=True)
        err = np.abs(s.sample(out, pts) - want)
        rows.append(
            dict(
                method=method,
                h=h,
                steps=info.iterations,
                change=info.change,
                mean_error=float(err.mean()),
                max_error=float(err.max()),
                seconds=time.perf_counter() - t0,
            )
        )
        print(json.dumps(rows[-1]), flush=True)
    return rows


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--json")
    ap.add_argument("--quick", action="store_true")
    a = ap.parse_args()
    fine = () if a.quick else (0.0125,)
    result = {
        "convergence": convergence("sphere", (0.1, 0.05, 0.025) + fine)
        + convergence("torus", (0.05, 0.025) + fine),
        "edge": edge(),
        "meshes": mesh_rows(a.quick),
    }
    if a.json:
        Path(a.json).write_text(json.dumps(result, indent=1))


if __name__ == "__main__":
    main()

"""Accuracy and speed of the intrinsic heat flow on implicit surfaces, in one run.

    python benchmarks/surface_accuracy.py [--json PATH] [--quick]

1. Convergence on the unit sphere, heat flow to t = 0.1, at spacing 0.1, 0.05, 0.025: u = xy
   (exact: exp(-6t) xy) and u = exp(3z) (exact: Legendre series, each P_l decays as
   exp(-l(l+1)t)); max error over 2000 points on the sphere measured through surf.sample
   (tricubic), for appendix E's forward/backward scheme and for the alternating one.
2. The approach users would otherwise pick: a cotangent Laplacian on an icosphere (built here
   with scipy.sparse, lumped barycentric mass), explicit Euler at its stability limit to the
   same t; error at the vertices (which lie on the sphere), against the number of unknowns.
3. Per-step time against band size on 64^3, 128^3 and 256^3 grids (a sphere filling the box),
   and the effective bandwidth of the bytes a band step must move, against a device copy and
   against a band copy (the same bytes over the same runs, no arithmetic).
4. Turk's reaction-diffusion on a sphere of radius 25 cells: the pattern's dominant
   spherical-harmonic degree against the planar linear stability analysis (about 9.9 cells).
5. Mesh to signed distance: ImplicitSurface.from_mesh on a torus and an icosphere mesh at
   several resolutions, against trimesh's own signed_distance (timed on a sample of band
   cells and extrapolated): time, time per band cell, the largest difference of |psi| from
   the exact point-mesh distance and sign disagreements with trimesh's inside test on the
   sample, and whether flipping half the faces changes psi. Then the same meshes with a hole
   many cells wide (a cap of faces removed) at 64 and 128 cells across: from_mesh's time,
   sign errors at the band cells against the exact shape (away from the hole), and the
   winding number's cost per point, two-level far field (over all band cells) against the
   exact triangle sum (over the cells of a few random 8^3 tiles, so both run in full
   chunks), with the far field's largest difference from the exact sum there. Last, heat
   flow on an icosphere whose polar hole from_mesh closed, with and without reinitialising
   the cells of the hole's rim (section 5c).
6. The band's two storages in one run: the band lists over the dense padded grid (kernels/
   surface/heat.cl) and the dense bricks (kernels/surface/bricks.cl) at each brick size, a heat
   step plus
   the re-extension of what the next step reads, on 64^3 to 256^3 grids (--storage-sizes;
   512 if memory allows): time per step against a device copy of the whole grid (the
   yardstick: at most one copy is the target), per band cell, and the effective bandwidth of
   the useful bytes (12 a node cell stepped, 24 a reach cell re-extended: index, stencil,
   value) and of the bytes the storage moves (the step's over every cell of the bricks it
   visits, or of the lists' runs), against the copy's. Then the sphere's accuracy table
   with both storages (section 1's cases, alternating scheme).
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
import time
from pathlib import Path

import numpy as np

from clpde.surface.exact import exp3z_exact, sphere_points, xy_exact

# The benchmarks' own kernels: no part of the library, built by their path.
ROOFLINE_CL = str(Path(__file__).resolve().parent / "kernels" / "roofline.cl")


RESULTS = Path(__file__).resolve().parent / "results" / "surface_accuracy.json"


CASES = {
    "xy": (lambda x, y, z: x * y, xy_exact),
    "exp3z": (lambda x, y, z: np.exp(3 * z), lambda p, t: exp3z_exact(p[:, 2], t)),
}


def convergence(spacings, t=0.1):
    from clpde.surface import ImplicitSurface

    pts = sphere_points(2000)
    rows = []
    for h in spacings:
        surf = ImplicitSurface.sphere(1.0, h)
        for name, (f, exact) in CASES.items():
            u = surf.field(f)
            for alternate in (False, True):
                start = time.perf_counter()
                v = surf.heat(u, t, alternate=alternate)
                seconds = time.perf_counter() - start
                err = float(np.abs(surf.sample(v, pts) - exact(pts, t)).max())
                rows.append(
                    {
                        "case": name,
                        "spacing": h,
                        "alternate": alternate,
                        "error": err,
                        "seconds": seconds,
                        "step_band": surf.step_band.n,
                        "ext_band": surf.ext_band.n,
                        "node_band": surf.node_band.n,
                    }
                )
    for row in rows:
        prev = [
            r
            for r in rows
            if r["case"] == row["case"]
            and r["alternate"] == row["alternate"]
            and r["spacing"] == 2 * row["spacing"]
        ]
        row["order"] = math.log2(prev[0]["error"] / row["error"]) if prev else None
    return rows


def cotangent_laplacian(vertices, faces):
    """Stiffness matrix L (negative semidefinite) and lumped barycentric masses."""
    import scipy.sparse as sp

    n = len(vertices)
    rows, cols, vals = [], [], []
    area = np.zeros(n)
    for k in range(3):
        i, j, o = faces[:, k], faces[:, (k + 1) % 3], faces[:, (k + 2) % 3]
        a = vertices[i] - vertices[o]
        b = vertices[j] - vertices[o]
        cot = np.einsum("ij,ij->i", a, b) / np.linalg.norm(np.cross(a, b), axis=1)
        rows += [i, j]
        cols += [j, i]
        vals += [0.5 * cot, 0.5 * cot]
    tri_area = 0.5 * np.linalg.norm(
        np.cross(
            vertices[faces[:, 1]] - vertices[faces[:, 0]],
            vertices[faces[:, 2]] - vertices[faces[:, 0]],
        ),
        axis=1,
    )
    for k in range(3):
        np.add.at(area, faces[:, k], tri_area / 3)
    off = sp.csr_matrix(
        (np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(n, n)
    )
    stiffness = off - sp.diags(np.asarray(off.sum(axis=1)).ravel())
    return stiffness, area


def icosphere_heat(subdivisions, t=0.1):
    import scipy.sparse as sp
    import scipy.sparse.linalg as sla
    import trimesh

    mesh = trimesh.creation.icosphere(subdivisions=subdivisions, radius=1.0)
    v, f = np.asarray(mesh.vertices), np.asarray(mesh.faces)
    stiffness, mass = cotangent_laplacian(v, f)
    op = sp.diags(1 / mass) @ stiffness
    lam = abs(sla.eigs(op, k=1, which="LM", return_eigenvectors=False)[0])
    limit = 2 / lam
    rows = []
    for name, (fn, exact) in CASES.items():
        u = fn(v[:, 0], v[:, 1], v[:, 2]).astype(np.float64)
        steps = math.ceil(t / limit)
        dt = t / steps
        start = time.perf_counter()
        for _ in range(steps):
            u = u + dt * (op @ u)
        seconds = time.perf_counter() - start
        err = float(np.abs(u - exact(v, t)).max())
        rows.append(
            {
                "case": name,
                "subdivisions": subdivisions,
                "vertices": len(v),
                "error": err,
                "steps": steps,
                "seconds": seconds,
            }
        )
    return rows


def step_timing(sizes, steps=20):
    return [_time_size(n, steps) for n in sizes]


def _time_size(n, steps):
    import pyopencl as cl
    import pyopencl.array as cla

    from clpde.surface import ImplicitSurface
    from clpde.surface.storage import BandFlow, _offsets

    # from_function pads the unit sphere's box by 8 cells a side: n cells in all
    spacing = 2.0 / (n - 17)
    surf = ImplicitSurface.sphere(1.0, spacing)
    g = surf.grid
    flow = BandFlow(surf, surf.field(lambda x, y, z: x * y))
    kernel = g.kernel("surface/heat.cl", "heat_step", WEIGHTED=0)
    r = g.scalar(0.1)
    q = surf.runtime.queue

    def one_step():
        g.launch_runs(
            kernel,
            surf.step_runs,
            flow.cur.data,
            flow.tmp.data,
            surf.psi_dev.data,
            r,
            *_offsets(g, 0),
            *g.strides(),
        )

    def run(what, count):
        q.finish()
        start = time.perf_counter()
        for _ in range(count):
            what()
        q.finish()
        return (time.perf_counter() - start) / count

    band_copy = g.kernel(ROOFLINE_CL, "band_copy")

    def one_band_copy():
        g.launch_runs(band_copy, surf.step_runs, flow.cur.data, flow.tmp.data, surf.psi_dev.data)

    # the same kernel over every cell of whole rows of the box (2 cells from its edges): the
    # dense stencil's own ceiling, which no storage of the band can beat
    dense = _dense_runs(g, q)
    dense_cells = int((dense.end.get() - dense.start.get()).sum())

    def one_dense_step():
        g.launch_runs(
            kernel,
            dense,
            flow.cur.data,
            flow.tmp.data,
            surf.psi_dev.data,
            r,
            *_offsets(g, 0),
            *g.strides(),
        )

    run(one_step, 2)
    run(flow.after_step, 2)
    run(one_band_copy, 2)
    run(one_dense_step, 1)
    t_step = run(one_step, steps)
    t_ext = run(flow.after_step, steps)
    t_band_copy = run(one_band_copy, steps)
    t_dense = run(one_dense_step, max(2, steps // 4))
    # bytes each kernel must move at least: the step reads u and psi and writes tmp on each
    # node (its runs cost two list reads each); the re-extension reads the index, the
    # stencil's base and three offsets and writes one value per reach cell (the
    # interpolation's reads are neighbours, counted once through the written value).
    b_step = surf.node_band.n * 12 + surf.step_runs.n * 8
    b_ext = surf.reach_band.n * (4 + 4 + 12 + 4)
    nbytes = 256 * 2**20
    a = cla.empty(q, nbytes // 4, np.float32)
    a.fill(1.0)
    b = cla.zeros_like(a)

    def copy():
        cl.enqueue_copy(q, b.data, a.data)

    run(copy, 2)
    t_copy = run(copy, 5)
    copy_bw = 2 * nbytes / t_copy
    return {
        "grid": list(surf.shape),
        "step_band": surf.step_band.n,
        "ext_band": surf.ext_band.n,
        "node_band": surf.node_band.n,
        "reach_band": surf.reach_band.n,
        "runs": surf.step_runs.n,
        "step_ms": 1e3 * t_step,
        "extend_ms": 1e3 * t_ext,
        "ns_per_cell": 1e9 * (t_step + t_ext) / surf.ext_band.n,
        "step_gbs": b_step / t_step / 1e9,
        "extend_gbs": b_ext / t_ext / 1e9,
        "band_copy_ms": 1e3 * t_band_copy,
        "band_copy_gbs": b_step / t_band_copy / 1e9,
        "dense_step_ms": 1e3 * t_dense,
        "dense_step_gbs": 12 * dense_cells / t_dense / 1e9,
        "copy_gbs": copy_bw / 1e9,
    }


def storage_table(sizes, steps=10, reps=5):
    print(
        "\n6. band storage: lists over the dense grid against dense bricks (heat step + "
        "re-extension"
        f"\n   of the reach band; best of {reps} runs of {steps} steps, all variants "
        "interleaved)"
    )
    print(
        f"{'grid':>9} {'storage':>8} {'ext band':>9} {'stored':>9} {'visited':>9} {'step ms':>8} "
        f"{'ext ms':>7} "
        f"{'x copy':>7} {'ns/cell':>8} {'useful GB/s':>11} {'stored GB/s':>11} {'copy GB/s':>9}"
    )
    rows = [row for n in sizes for row in _storage_size(n, steps, reps)]
    print(
        "   (stored: the padded grid's cells for the lists, the bricks' for bricks; visited: the "
        "cells the\n"
        "    step updates, the runs' or the bricks' rows holding a node; x copy: a step's time "
        "over a device copy\n"
        "    of the whole padded grid, float32; stored GB/s: the bytes the step and the "
        "re-extension move)"
    )
    return rows


def _storage_size(n, steps, reps):
    import pyopencl as cl
    import pyopencl.array as cla

    from clpde.bricks import BRICK_SIZES
    from clpde.surface import ImplicitSurface
    from clpde.surface.storage import BandFlow, BrickFlow, _offsets, _signs

    surf = ImplicitSurface.sphere(1.0, 2.0 / (n - 17))
    g, q = surf.grid, surf.runtime.queue
    u = surf.field(lambda x, y, z: x * y)
    r = g.scalar(0.1)
    variants = {}
    flow = BandFlow(surf, u)
    k_list = g.kernel("surface/heat.cl", "heat_step", WEIGHTED=0)

    def list_step():
        g.launch_runs(
            k_list,
            surf.step_runs,
            flow.cur.data,
            flow.tmp.data,
            surf.psi_dev.data,
            r,
            *_offsets(g, 0),
            *g.strides(),
        )

    runs = surf.step_runs
    run_cells = int((runs.end.get()[: runs.n] - runs.start.get()[: runs.n]).sum())
    variants["lists"] = (
        list_step,
        flow.after_step,
        g.volume,
        run_cells,
        12 * run_cells + 8 * runs.n,
    )
    for brick in BRICK_SIZES:
        surf.band.brick = brick
        bf = BrickFlow(surf, u)
        k_brick = bf.kernel("surface/bricks.cl", "bricks_heat_step", WEIGHTED=0)

        def brick_step(bf=bf, k=k_brick):
            bf.bricks.launch(
                k, bf.cur.data, bf.tmp.data, bf.psi.data, r, *_signs(0), bf.bricks.node_rows.data
            )

        bx, by, bz = brick
        visited = int(bf.bricks.node_rows.get().astype(np.int64).sum()) * bx  # rows with a node
        apron = (bx + 3) * (by + 3) * (bz + 3) / (bx * by * bz)  # the step writes the aprons too
        variants["x".join(map(str, brick))] = (
            brick_step,
            bf.after_step,
            bf.bricks.stored_cells,
            visited,
            int(visited * (8 + 4 * apron)),
        )
    a = cla.empty(q, g.volume, np.float32)
    a.fill(1.0)
    b = cla.empty_like(a)

    def timed(fn):
        q.finish()
        start = time.perf_counter()
        for _ in range(steps):
            fn()
        q.finish()
        return (time.perf_counter() - start) / steps

    def copy():
        cl.enqueue_copy(q, b.data, a.data)

    best = {name: [np.inf, np.inf] for name in variants}
    t_copy = np.inf
    for step, ext, *_ in variants.values():  # warm up (and compile)
        step(), ext()
    for _ in range(reps):
        t_copy = min(t_copy, timed(copy))
        for name, (step, ext, *_) in variants.items():
            best[name][0] = min(best[name][0], timed(step))
            best[name][1] = min(best[name][1], timed(ext))
    copy_gbs = 2 * a.nbytes / t_copy / 1e9
    useful = 12 * surf.node_band.n + 24 * surf.reach_band.n
    rows = []
    for name, (_, _, stored, visited, step_bytes) in variants.items():
        ts, te = best[name]
        row = {
            "grid": n,
            "storage": name,
            "ext_band": surf.ext_band.n,
            "node_band": surf.node_band.n,
            "reach_band": surf.reach_band.n,
            "stored_cells": stored,
            "visited_cells": visited,
            "step_ms": 1e3 * ts,
            "extend_ms": 1e3 * te,
            "copy_ms": 1e3 * t_copy,
            "x_copy": (ts + te) / t_copy,
            "ns_per_cell": 1e9 * (ts + te) / surf.ext_band.n,
            "useful_gbs": useful / (ts + te) / 1e9,
            "stored_gbs": (step_bytes + 24 * surf.reach_band.n) / (ts + te) / 1e9,
            "copy_gbs": copy_gbs,
        }
        rows.append(row)
        print(
            f"{n:>7}^3 {name:>8} {row['ext_band']:9d} {stored:9d} {visited:9d} "
            f"{row['step_ms']:8.2f} "
            f"{row['extend_ms']:7.2f} {row['x_copy']:7.2f} {row['ns_per_cell']:8.2f} "
            f"{row['useful_gbs']:11.2f} {row['stored_gbs']:11.2f} {copy_gbs:9.2f}"
        )
    return rows


def storage_accuracy(spacings, t=0.1):
    from clpde.surface import ImplicitSurface

    pts = sphere_points(2000)
    print(
        "\n6b. heat flow on the unit sphere to t = 0.1 in both storages (max error through "
        "surf.sample)"
    )
    print(f"{'case':6} {'h':>6} {'lists':>10} {'bricks':>10} {'ratio':>6} {'order':>6}")
    rows = []
    for h in spacings:
        surf = ImplicitSurface.sphere(1.0, h)
        for name, (f, exact) in CASES.items():
            u = surf.field(f)
            err = {}
            for storage in ("lists", "bricks"):
                surf.storage = storage
                err[storage] = float(
                    np.abs(surf.sample(surf.heat(u, t), pts) - exact(pts, t)).max()
                )
            prev = [r for r in rows if r["case"] == name and r["spacing"] == 2 * h]
            order = math.log2(prev[0]["bricks"] / err["bricks"]) if prev else None
            rows.append(
                {
                    "case": name,
                    "spacing": h,
                    **err,
                    "ratio": err["bricks"] / err["lists"],
                    "order": order,
                }
            )
            o = f"{order:.2f}" if order is not None else "-"
            print(
                f"{name:6} {h:6.3f} {err['lists']:10.3e} {err['bricks']:10.3e} "
                f"{err['bricks'] / err['lists']:6.3f} {o:>6}"
            )
    return rows


def _dense_runs(g, q):
    """Runs covering whole rows of the box, 2 cells in from its edges on every side."""
    import pyopencl.array as cla

    from clpde.grid3d import BandRuns

    zs, ys = np.meshgrid(np.arange(2, g.nz - 2), np.arange(2, g.ny - 2), indexing="ij")
    base = (zs.ravel() + g.ghost) * int(g.sxy) + (ys.ravel() + g.ghost) * int(g.sx) + g.ghost
    start, end = (base + 2).astype(np.int32), (base + g.nx - 2).astype(np.int32)
    return BandRuns(None, cla.to_device(q, start), cla.to_device(q, end), len(start))


def degree_power(values, points, lmax=40):
    """Energy per spherical-harmonic degree of samples at quasi-uniform points on the unit
    sphere, by the addition theorem: sum_m |a_lm|^2 = (2l+1)/(4 pi) (4 pi/N)^2 f.P_l(X).f."""
    f = values - values.mean()
    x = np.clip(points @ points.T, -1, 1)
    n = len(points)
    p_prev, p_cur = np.ones_like(x), x.copy()
    power = [0.0]
    for ell in range(1, lmax + 1):
        if ell > 1:
            p_prev, p_cur = p_cur, ((2 * ell - 1) * x * p_cur - (ell - 1) * p_prev) / ell
        power.append((2 * ell + 1) / (4 * np.pi) * (4 * np.pi / n) ** 2 * float(f @ p_cur @ f))
    return np.array(power)


def turk_wavelength(iterations=12000, radius_cells=25):
    from clpde.surface import ImplicitSurface, textures

    h = 1.0 / radius_cells
    surf = ImplicitSurface.sphere(1.0, h)
    start = time.perf_counter()
    ab = surf.reaction_diffusion(iterations, seed=3, params=textures.TURK)
    seconds = time.perf_counter() - start
    pts = sphere_points(3000)
    power = degree_power(surf.sample(ab[0], pts), pts)
    l_star = int(np.argmax(power[1:]) + 1)
    measured = 2 * np.pi * radius_cells / np.sqrt(l_star * (l_star + 1))
    return {
        "iterations": iterations,
        "radius_cells": radius_cells,
        "dominant_degree": l_star,
        "measured_wavelength_cells": float(measured),
        "predicted_wavelength_cells": textures.turk_linear_wavelength(),
        "power": power.tolist(),
        "seconds": seconds,
        "band": surf.ext_band.n,
    }


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--json", type=Path, default=RESULTS)
    parser.add_argument("--quick", action="store_true", help="coarse grids only (a smoke test)")
    parser.add_argument(
        "--sections", default="123456", help="which sections to run (default: 123456)"
    )
    parser.add_argument(
        "--storage-sizes",
        default="64,128,217,256",
        help="grid sizes of section 6 (add 512 where memory allows)",
    )
    args = parser.parse_args(argv)
    import clpde

    rt = clpde.get_runtime()
    device = f"{rt.device.name.strip()} ({rt.type}, {rt.platform.name.strip()})"
    spacings = [0.1, 0.05] if args.quick else [0.1, 0.05, 0.025]
    results = {"device": device}
    print(f"device: {device}")
    if "1" in args.sections or "2" in args.sections:
        results.update(accuracy(spacings, args.quick))
    if "3" in args.sections:
        results["timing"] = timing_table([64, 128] if args.quick else [64, 128, 256])
    if "4" in args.sections:
        rd = turk_wavelength(3000 if args.quick else 12000)
        results["turk"] = rd
        print(
            f"\n4. Turk reaction-diffusion on a sphere of radius {rd['radius_cells']} cells, "
            f"{rd['iterations']} iterations ({rd['seconds']:.0f} s, band {rd['band']} cells): "
            f"dominant degree {rd['dominant_degree']}, wavelength "
            f"{rd['measured_wavelength_cells']:.1f} "
            f"cells; linear stability predicts {rd['predicted_wavelength_cells']:.1f} cells"
        )
    if "5" in args.sections:
        results["mesh_sdf"] = mesh_sdf_table([64, 128] if args.quick else [64, 128, 256])
        results["mesh_sdf_holed"] = holed_mesh_table([64, 128])
        results["closed_hole_heat"] = closed_hole_heat()
    if "6" in args.sections:
        sizes = [64, 128] if args.quick else [int(v) for v in args.storage_sizes.split(",")]
        results["storage"] = storage_table(sizes)
        results["storage_accuracy"] = storage_accuracy(spacings)
    args.json.parent.mkdir(parents=True, exist_ok=True)
    tmp = args.json.with_suffix(".tmp")
    tmp.write_text(json.dumps(results, indent=1))
    os.replace(tmp, args.json)
    print(f"\nwrote {args.json}")


def mesh_sdf_table(resolutions, sample=1500):
    import trimesh

    from clpde.surface import ImplicitSurface

    print(
        "\n5. mesh -> signed distance: clpde from_mesh against trimesh.proximity.signed_distance"
        f"\n   (trimesh timed on {sample} band cells, extrapolated to the band)"
    )
    meshes = {
        "torus 1/0.4": trimesh.creation.torus(1.0, 0.4, major_sections=96, minor_sections=48),
        "icosphere 5": trimesh.creation.icosphere(subdivisions=5),
    }
    rng = np.random.default_rng(0)
    rows = []
    print(
        f"{'mesh':12} {'faces':>6} {'grid':>12} {'band':>8} {'clpde s':>8} {'ns/cell':>8} "
        f"{'trimesh s (est.)':>16} {'ratio':>7} {'max |d| err':>11} {'sign diff':>9} "
        f"{'flip-proof':>10}"
    )
    for name, mesh in meshes.items():
        flipped = mesh.copy()
        flipped.faces[::2] = flipped.faces[::2, ::-1]  # half the faces turned inside out
        for res in resolutions:
            ImplicitSurface.from_mesh(mesh, resolution=min(res, 32))  # warm the kernels up
            start = time.perf_counter()
            surf = ImplicitSurface.from_mesh(mesh, resolution=res)
            seconds = time.perf_counter() - start
            band = np.argwhere(np.abs(surf.psi) < surf.outer * surf.spacing)
            pick = band[rng.choice(len(band), min(sample, len(band)), replace=False)]
            points = surf.origin + pick[:, ::-1] * surf.spacing  # (z, y, x) -> (x, y, z)
            start = time.perf_counter()
            theirs = trimesh.proximity.signed_distance(mesh, points)  # positive inside
            t_theirs = (time.perf_counter() - start) * len(band) / len(pick)
            ours = surf.psi[tuple(pick.T)]
            err = float(np.abs(np.abs(ours) - np.abs(theirs)).max() / surf.spacing)
            sign_diff = int(np.sum((ours < 0) != (theirs > 0)))
            again = ImplicitSurface.from_mesh(flipped, resolution=res)
            flip_proof = bool(np.array_equal(np.sign(again.psi), np.sign(surf.psi)))
            row = {
                "mesh": name,
                "faces": len(mesh.faces),
                "grid": list(surf.shape),
                "band": len(band),
                "seconds": seconds,
                "ns_per_cell": 1e9 * seconds / len(band),
                "trimesh_seconds_estimate": t_theirs,
                "ratio": t_theirs / seconds,
                "max_abs_distance_error_cells": err,
                "sign_disagreements": sign_diff,
                "sample": len(pick),
                "flipped_faces_same_sign": flip_proof,
            }
            rows.append(row)
            print(
                f"{name:12} {row['faces']:6d} {'x'.join(map(str, row['grid'])):>12} "
                f"{row['band']:8d} "
                f"{seconds:8.2f} {row['ns_per_cell']:8.0f} {t_theirs:16.1f} {row['ratio']:7.0f} "
                f"{err:11.1e} {sign_diff:9d} {flip_proof!s:>10}"
            )
    print(
        "   (max |d| err: largest difference of |psi| from trimesh's exact distance, in cells;"
        "\n    sign diff: sample cells whose side differs from trimesh's inside test)"
    )
    return rows


def holed_mesh_table(resolutions, exact_points=3000):
    import warnings

    import trimesh

    from clpde.surface import ImplicitSurface
    from clpde.surface.mesh_sdf import grid_for_mesh
    from clpde.surface.winding import WindingNumbers

    print(
        "\n5b. meshes with a hole many cells wide: from_mesh (sign by the winding number where "
        "the\n"
        "    flood fill leaks) and the winding number per point, two-level against the exact sum"
    )
    sphere = trimesh.creation.icosphere(subdivisions=5)
    torus = trimesh.creation.torus(1.0, 0.4, major_sections=96, minor_sections=48)
    cases = {  # mesh, centre of the removed cap, its radius, exact signed distance
        "icosphere 5": (sphere, [0, 0, 1], 0.25, lambda p: np.linalg.norm(p, axis=1) - 1),
        "torus 1/0.4": (
            torus,
            [1.4, 0, 0],
            0.25,
            lambda p: np.hypot(np.hypot(p[:, 0], p[:, 1]) - 1, p[:, 2]) - 0.4,
        ),
    }
    rng = np.random.default_rng(1)
    rows = []
    print(
        f"{'mesh':12} {'faces':>6} {'grid':>12} {'band':>8} {'from_mesh s':>11} {'sign err':>8} "
        f"{'fast us/pt':>10} {'exact us/pt':>11} {'speed-up':>8} {'max |dw|':>9}"
    )
    for name, (mesh, centre, radius, sdf) in cases.items():
        gone = np.linalg.norm(mesh.triangles_center - centre, axis=1) < radius
        holed = mesh.copy()
        holed.update_faces(~gone)
        for res in resolutions:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                ImplicitSurface.from_mesh(holed, resolution=32)  # warm the kernels up
                start = time.perf_counter()
                surf = ImplicitSurface.from_mesh(holed, resolution=res)
                seconds = time.perf_counter() - start
            h = surf.spacing
            cells = np.argwhere(surf._mesh_face >= 0)  # the band, (z, y, x)
            pts = surf.origin + cells[:, ::-1] * h
            # sign against the exact shape, away from the hole and from the surface itself
            away = (np.linalg.norm(pts - centre, axis=1) > radius + 3 * h) & (
                np.abs(sdf(pts)) > 0.01
            )
            sign_err = int(np.sum((surf.psi[tuple(cells[away].T)] < 0) != (sdf(pts[away]) < 0)))
            origin, hg, _ = grid_for_mesh(holed, None, res, 8)
            wn = WindingNumbers((np.asarray(holed.triangles) - origin) / hg)
            local = (pts - origin) / hg
            start = time.perf_counter()
            wn(local)
            t_fast = (time.perf_counter() - start) / len(local)
            tiles = np.floor(local / 8).astype(np.int64)
            key = (tiles[:, 2] * 4096 + tiles[:, 1]) * 4096 + tiles[:, 0]
            chosen = []
            for t in rng.permutation(np.unique(key)):
                chosen.append(np.flatnonzero(key == t))
                if sum(map(len, chosen)) >= exact_points:
                    break
            sub = local[np.concatenate(chosen)]
            start = time.perf_counter()
            w_exact = wn(sub, exact=True)
            t_exact = (time.perf_counter() - start) / len(sub)
            dw = float(np.abs(wn(sub) - w_exact).max())
            row = {
                "mesh": name,
                "faces": len(holed.faces),
                "removed_faces": int(gone.sum()),
                "grid": list(surf.shape),
                "band": len(cells),
                "seconds": seconds,
                "sign_errors_away_from_hole": sign_err,
                "checked_cells": int(away.sum()),
                "winding_us_per_point_fast": 1e6 * t_fast,
                "winding_us_per_point_exact": 1e6 * t_exact,
                "exact_points": len(sub),
                "max_fast_minus_exact": dw,
            }
            rows.append(row)
            print(
                f"{name:12} {row['faces']:6d} {'x'.join(map(str, row['grid'])):>12} "
                f"{len(cells):8d} "
                f"{seconds:11.2f} {sign_err:8d} {1e6 * t_fast:10.2f} {1e6 * t_exact:11.1f} "
                f"{t_exact / t_fast:8.0f} {dw:9.1e}"
            )
    print(
        "   (sign err: band cells farther than 3 cells from the hole and 0.01 from the surface "
        "whose\n"
        "    side differs from the exact shape's; max |dw|: two-level minus exact winding "
        "number)"
    )
    return rows


def closed_hole_heat(resolution=40, t=0.1):
    """Heat flow of u = xy to t on a unit icosphere with a polar hole (faces within 0.45 of
    the pole), error at points with z < 0.7 against exp(-6t) xy: the mesh closed, the hole
    closed by from_mesh (its rim's cells reinitialised), and the same psi before that step
    (mesh_to_sdf's, where psi jumps across the closing sheet)."""
    import warnings

    import trimesh

    from clpde.surface import ImplicitSurface
    from clpde.surface.mesh_sdf import grid_for_mesh, mesh_to_sdf

    mesh = trimesh.creation.icosphere(4, radius=1.0)
    holed = mesh.copy()
    holed.update_faces(np.linalg.norm(mesh.triangles_center - [0, 0, 1], axis=1) >= 0.45)
    pts = sphere_points(2000)
    pts = pts[pts[:, 2] < 0.7] * 0.999  # the icosphere lies just inside the unit sphere

    def error(surf):
        v = surf.heat(surf.field(lambda x, y, z: x * y), t=t)
        return float(np.abs(surf.sample(v, pts) - xy_exact(pts, t)).max())

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        closed = ImplicitSurface.from_mesh(mesh, resolution=resolution)
        patched = ImplicitSurface.from_mesh(holed, resolution=resolution)
        origin, h, shape = grid_for_mesh(holed, None, resolution, int(np.ceil(patched.outer)) + 4)
        raw, _, _ = mesh_to_sdf(holed, origin, h, shape, patched.outer + 3.0)
        unpatched = ImplicitSurface(raw, h, origin)
    row = {
        "closed": error(closed),
        "hole_closed_and_reinitialised": error(patched),
        "hole_closed_jumping_psi": error(unpatched),
        "spacing": h,
    }
    print(
        "\n5c. heat flow of xy to t = 0.1 on an icosphere with a polar hole (max error where z < "
        "0.7):"
        f"\n   closed mesh {row['closed']:.2e}; hole closed, rim reinitialised "
        f"{row['hole_closed_and_reinitialised']:.2e}; hole closed, psi jumping across it "
        f"{row['hole_closed_jumping_psi']:.2e} (h = {h:.3f})"
    )
    return row


def accuracy(spacings, quick):
    print("\n1. heat flow on the unit sphere to t = 0.1 (max error through surf.sample)")
    conv = convergence(spacings)
    print(f"{'case':6} {'scheme':10} {'h':>6} {'band':>8} {'error':>10} {'order':>6} {'time s':>7}")
    for r in conv:
        order = f"{r['order']:.2f}" if r["order"] is not None else "-"
        scheme = "alternate" if r["alternate"] else "forward"
        print(
            f"{r['case']:6} {scheme:10} {r['spacing']:6.3f} {r['ext_band']:8d} "
            f"{r['error']:10.2e} {order:>6} {r['seconds']:7.2f}"
        )

    print("\n2. cotangent Laplacian on an icosphere, explicit Euler (error at the vertices)")
    cot = [row for s in ((3, 4) if quick else (3, 4, 5, 6, 7)) for row in icosphere_heat(s)]
    print(f"{'case':6} {'subdiv':>6} {'vertices':>8} {'steps':>6} {'error':>10} {'time s':>7}")
    for r in cot:
        print(
            f"{r['case']:6} {r['subdivisions']:6d} {r['vertices']:8d} {r['steps']:6d} "
            f"{r['error']:10.2e} {r['seconds']:7.2f}"
        )

    print(
        "\n   at equal numbers of unknowns (cotangent error interpolated log-log at the band's "
        "size):"
    )
    for r in conv:
        for name in ("node_band", "step_band", "ext_band"):
            rows = sorted((c["vertices"], c["error"]) for c in cot if c["case"] == r["case"])
            n, e = np.log([a for a, _ in rows]), np.log([b for _, b in rows])
            r[f"cot_error_at_{name}"] = float(np.exp(np.interp(np.log(r[name]), n, e)))
        scheme = "alternate" if r["alternate"] else "forward"
        print(
            f"   {r['case']:6} {scheme:10} h={r['spacing']:.3f}: error / cotangent error = "
            f"{r['error'] / r['cot_error_at_node_band']:.2f} (the nodes: the cells a step "
            "updates), "
            f"{r['error'] / r['cot_error_at_step_band']:.2f} (step band), "
            f"{r['error'] / r['cot_error_at_ext_band']:.2f} (whole band)"
        )

    return {"convergence": conv, "cotangent": cot}


def timing_table(sizes):
    print(
        "\n3. per-step time against band size (heat step on the nodes + re-extension of what the "
        "step reads;"
        "\n   ns/cell per cell of the whole extension band, the band a result covers)"
    )
    timing = step_timing(sizes)
    print(
        f"{'grid':>14} {'ext band':>9} {'nodes':>8} {'reach':>8} {'runs':>7} {'step ms':>8} "
        f"{'ext ms':>7} "
        f"{'ns/cell':>8} {'step GB/s':>9} {'ext GB/s':>8} {'band copy GB/s':>14} "
        f"{'dense step GB/s':>15} "
        f"{'copy GB/s':>9}"
    )
    for r in timing:
        print(
            f"{'x'.join(map(str, r['grid'])):>14} {r['ext_band']:9d} {r['node_band']:8d} "
            f"{r['reach_band']:8d} "
            f"{r['runs']:7d} {r['step_ms']:8.2f} {r['extend_ms']:7.2f} {r['ns_per_cell']:8.2f} "
            f"{r['step_gbs']:9.2f} {r['extend_gbs']:8.2f} {r['band_copy_gbs']:14.2f} "
            f"{r['dense_step_gbs']:15.2f} {r['copy_gbs']:9.2f}"
        )
    print(
        "   (band copy: v = u + psi over the step's runs, the step's essential bytes with its "
        "access\n"
        "    pattern and no arithmetic: the band's own roofline; dense step: the heat step "
        "over every\n"
        "    cell of whole rows of the box, 12 bytes a cell: the stencil's own ceiling)"
    )
    return timing


if __name__ == "__main__":
    sys.exit(main())

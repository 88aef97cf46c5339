"""How far `clpde regions MESH` moves ordinary meshes: trimesh's torus, capsule and box at
the command line's default resolution, with each surface flow and its default time.

For each run: whether it finished (before the grid was padded to the flow's reach,
morph-sphere stopped at the volume's border on these meshes), the mean vertex displacement
(the starting surface's vertices' mean distance to the final surface) as a share of the
bounding box's diagonal, the largest displacement in grid cells, the grid and the time.
The target: a mean displacement of at least 5% of the diagonal with the default flow.

    python benchmarks/regions_mesh_motion.py [--flows morph-sphere,gaussian] [--resolution 96]
"""

from __future__ import annotations

import argparse
import json
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]


def meshes():
    import trimesh

    return {
        "torus": trimesh.creation.torus(1.0, 0.3),  # 1,024 vertices
        "capsule": trimesh.creation.capsule(),
        "box": trimesh.creation.box(),
    }


def main() -> None:
    from clpde.cli.regions import (
        DEFAULT_FLOW,
        FLOWS,
        displacement_stats,
        mesh_scene,
        run_scene,
    )
    from clpde.imagedata import InputError

    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--flows", default=",".join(FLOWS))
    parser.add_argument("--resolution", type=int, default=96)
    parser.add_argument(
        "--json", type=Path, default=ROOT / "benchmarks/results/regions_mesh_motion.json"
    )
    args = parser.parse_args()
    rows = []
    print(f"default flow: {DEFAULT_FLOW}; resolution {args.resolution}")
    print(
        f"{'mesh':8s} {'flow':15s} {'ok':3s} {'mean/diag':>9s} {'max cells':>9s} "
        f"{'grid':>12s} {'s':>6s}"
    )
    with tempfile.TemporaryDirectory() as tmp:
        for name, mesh in meshes().items():
            path = Path(tmp) / f"{name}.ply"
            mesh.export(path)
            diagonal = float(np.linalg.norm(np.ptp(mesh.vertices, axis=0)))
            for flow in args.flows.split(","):
                start = time.perf_counter()
                row = {"mesh": name, "flow": flow, "resolution": args.resolution}
                try:
                    scene = mesh_scene(str(path), flow, args.resolution)
                    frames = run_scene(scene, saves=1)
                    mean, most = displacement_stats(scene, frames[-1], frames[0].mesh)
                    row |= {
                        "ok": True,
                        "mean_share": mean / diagonal,
                        "max_cells": most / scene.spacing,
                        "grid": list(scene.phi.shape[::-1]),
                        "t": frames[-1].time,
                    }
                except InputError as exc:
                    row |= {"ok": False, "error": str(exc)}
                row["seconds"] = time.perf_counter() - start
                rows.append(row)
                if row["ok"]:
                    print(
                        f"{name:8s} {flow:15s} yes {row['mean_share']:9.1%} "
                        f"{row['max_cells']:9.1f} {'x'.join(map(str, row['grid'])):>12s} "
                        f"{row['seconds']:6.0f}",
                        flush=True,
                    )
                else:
                    print(f"{name:8s} {flow:15s} no  {row['error'][:70]}", flush=True)
    args.json.parent.mkdir(parents=True, exist_ok=True)
    args.json.write_text(json.dumps(rows, indent=1))


if __name__ == "__main__":
    main()

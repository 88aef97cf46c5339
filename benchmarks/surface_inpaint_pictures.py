"""The pictures of docs/surface.md's inpainting section: vertex colours on trimesh meshes with a
patch removed, filled by clpde.surface.inpaint (harmonic and transport), drawn before and after.

    python benchmarks/surface_inpaint_pictures.py [OUTDIR]   (default docs/images)
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import imageio.v3 as iio
import numpy as np
import trimesh

from clpde.surface import inpaint
from clpde.surface.inpaint_files import _facing, coloured
from clpde.surface.render import render_mesh, with_title

ORANGE, NAVY = np.array([0.95, 0.6, 0.15]), np.array([0.1, 0.15, 0.45])


def stripes(v, phase):
    """Oblique stripes with soft edges, as RGB in 0..255."""
    t = 0.5 + 0.5 * np.tanh(3 * np.sin(phase))
    return np.rint(255 * (t[:, None] * ORANGE + (1 - t[:, None]) * NAVY)).astype(np.uint8)


def cases():
    torus = trimesh.creation.torus(1.0, 0.4, major_sections=160, minor_sections=64)
    v = torus.vertices
    phi = np.arctan2(v[:, 1], v[:, 0])
    tube = np.arctan2(v[:, 2], np.hypot(v[:, 0], v[:, 1]) - 1.0)
    yield "torus", torus, stripes(v, 5 * phi + 2 * tube), np.array([1.4, 0, 0]), 0.3
    ball = trimesh.creation.icosphere(5)
    v = ball.vertices
    yield "sphere", ball, stripes(v, 7 * (v[:, 0] + 0.5 * v[:, 2])), np.array([0.8, -0.6, 0]), 0.35


def main(outdir="docs/images"):
    out = Path(outdir)
    for name, mesh, rgb, centre, radius in cases():
        v = np.asarray(mesh.vertices)
        mask = np.linalg.norm(v - centre, axis=1) < radius
        # facing the patch from 40 degrees above it (a torus seen edge-on shows little)
        look = centre / np.linalg.norm(centre) + np.array([0, 0, 0.85])
        a, e = _facing(look / np.linalg.norm(look))
        panels = [with_title(render_mesh(coloured(mesh, rgb, mask), 320, a, e), "missing (grey)")]
        for method in ("harmonic", "transport"):
            t0 = time.perf_counter()
            filled, info = inpaint(mesh, rgb, mask, method=method, resolution=128, return_info=True)
            seconds = time.perf_counter() - t0
            err = np.abs(filled[mask].astype(int) - rgb[mask].astype(int)).mean()
            print(
                f"{name} {method}: {info.iterations} steps, {seconds:.1f} s, mean |error| "
                f"{err:.1f} levels of 255 over {int(mask.sum())} vertices",
                flush=True,
            )
            image = render_mesh(coloured(mesh, filled, None), 320, a, e)
            panels.append(with_title(image, f"{method} fill"))
        panels.append(with_title(render_mesh(coloured(mesh, rgb, None), 320, a, e), "original"))
        iio.imwrite(out / f"surface_inpaint_{name}.png", np.concatenate(panels, axis=1))


if __name__ == "__main__":
    main(*sys.argv[1:])

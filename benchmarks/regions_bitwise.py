"""Frames of clpde.track_region, saved for a bitwise check across a refactoring.

    PYTHONPATH=<tree A> python benchmarks/regions_bitwise.py save out/rbit/a.npz
    PYTHONPATH=<tree B> python benchmarks/regions_bitwise.py compare out/rbit/a.npz

A sphere of radius 0.7 on a 40^3 grid (spacing 0.08, float32) with two regions (a cap and
a half), moved three ways: expansion at speed 0.5, a translation, mean-curvature flow; three
frames each. Saved per frame: the level sets Phi and Phi-hat (keep_volumes), the face labels
and the mesh's vertices. kernels/common/extend.h was checked with it.
"""

import sys
import warnings

import numpy as np


def run() -> dict:
    import clpde

    warnings.simplefilter("ignore")
    print("results of", clpde.__file__)
    n, h = 40, 3.2 / 40
    ax = (np.arange(n) - (n - 1) / 2) * h
    z, y, x = np.meshgrid(ax, ax, ax, indexing="ij")
    phi = (np.sqrt(x**2 + y**2 + z**2) - 0.7).astype(np.float32)
    regions = [(0.4 - z).astype(np.float32), x.astype(np.float32) - 0.2]
    motions = {
        "beta": dict(beta=0.5, t=0.3),
        "vel": dict(velocity=np.array([0.3, 0.0, 0.1]), t=0.4),
        "mc": dict(beta="mean-curvature", t=0.05, weight=0.5),
    }
    res = {}
    for tag, kw in motions.items():
        frames = clpde.track_region(
            phi,
            regions,
            spacing=h,
            saves=2,
            origin=(ax[0],) * 3,
            progress=False,
            keep_volumes=True,
            **kw,
        )
        for k, f in enumerate(frames):
            res[f"{tag}_{k}_phi"] = f.phi
            res[f"{tag}_{k}_phihat"] = f.phihat
            res[f"{tag}_{k}_labels"] = f.face_labels
            res[f"{tag}_{k}_verts"] = np.asarray(f.mesh.vertices)
    return res


def compare(path: str) -> int:
    a, b = np.load(path), run()
    differ = 0
    for k in a.files:
        x, y = a[k], b[k]
        if not (x.dtype == y.dtype and x.shape == y.shape and x.tobytes() == y.tobytes()):
            differ += 1
            print(f"{k}: DIFFERS")
    print(f"{len(a.files)} arrays, {differ} differ")
    return differ


if __name__ == "__main__":
    if len(sys.argv) != 3 or sys.argv[1] not in ("save", "compare"):
        sys.exit(__doc__)
    if sys.argv[1] == "save":
        np.savez(sys.argv[2], **run())
    else:
        sys.exit(1 if compare(sys.argv[2]) else 0)

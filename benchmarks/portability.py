"""The complete Oclgrind sweep: every case of tests/portability/cases.py (every public
function, tiny inputs) under the simulator with data-race detection, at the OpenCL 1.2
minimum (32 KB local, 64 KB constant memory) and at NVIDIA's 48 KB of local memory; errors
reported and results against PoCL's. The test suite runs a subset of it (test_oclgrind.py).

    python benchmarks/portability.py [--limits 32768 49152] [--cases NAME ...]

Prints one row per case and limit: seconds under Oclgrind, Oclgrind's error count, the
largest difference from PoCL, and the kernels launched against the library's.
"""

from __future__ import annotations

import argparse
import json
import re
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests" / "portability"))
import cases  # noqa: E402
import test_oclgrind  # noqa: E402

KERNEL = re.compile(r"__kernel\s+(?:__attribute__\(\(.*?\)\)\s*)?void\s+(\w+)")


def library_kernels() -> set[str]:
    names = set()
    for path in (ROOT / "kernels").rglob("*.cl"):
        rel = path.relative_to(ROOT / "kernels").as_posix()
        for m in KERNEL.finditer(path.read_text()):
            names.add(f"{rel}:{m.group(1)}")
    return names


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--limits", type=int, nargs="+", default=[32768, 49152])
    parser.add_argument("--cases", nargs="+", default=list(cases.CASES))
    args = parser.parse_args()
    if test_oclgrind.OCLGRIND is None:
        sys.exit("oclgrind is not installed (apt-get install oclgrind)")
    pocl = {name: cases.CASES[name]() for name in args.cases}
    launched: set[str] = set()
    print("| case | local memory | seconds | Oclgrind errors | max difference from PoCL |")
    print("|---|---|---|---|---|")
    for limit in args.limits:
        for name in args.cases:
            with tempfile.TemporaryDirectory() as tmp:
                out = Path(tmp)
                t0 = time.perf_counter()
                status, log, output = test_oclgrind.run_under_oclgrind(out, limit, [name], 3600)
                seconds = time.perf_counter() - t0
                errors = log.count("Oclgrind - ") + log.count("data race")
                if status != 0:
                    print(f"| {name} | {limit // 1024} KB | {seconds:.0f} | failed | |")
                    print(output[-2000:], file=sys.stderr)
                    continue
                got = np.load(out / f"{name}.npz")
                diff = max(
                    float(np.abs(np.asarray(got[k], np.float64) - np.asarray(v, np.float64)).max())
                    for k, v in pocl[name].items()
                    if v is not None
                )
                launched |= set(json.loads((out / "kernels.json").read_text()))
            print(f"| {name} | {limit // 1024} KB | {seconds:.0f} | {errors} | {diff:.2g} |")
            if log.strip():
                print(log[:2000], file=sys.stderr)
    every = library_kernels()
    missed = sorted(every - launched - {"common/probe.cl:probe_double"})
    print(f"\nkernels launched: {len(launched & every)} of {len(every)} (probe.cl aside)")
    print("not launched by any case: " + (", ".join(missed) or "none"))


if __name__ == "__main__":
    main()

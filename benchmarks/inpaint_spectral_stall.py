"""Where a spectral window's picks could end: the numpy reference (tests/reference/spectral.py)
with every pick recorded, on grey 8-bit cases of the corpus's calibration half; each block's
own fill of its hole after each pick, against the truth, and stopping tests scored by it.

    PYTHONPATH=. python benchmarks/inpaint_spectral_stall.py [--cases NAME,...]

Prints, per test, the share of the picks kept and the change of the blocks' summed squared
error in dB (+: better), summed over all blocks and per case. Slow (the reference is a
Python loop): about a minute a case.
"""

from __future__ import annotations

import argparse
import inspect
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # tests.cases, tests.reference
from tests.cases import inpaint_corpus as corpus  # noqa: E402
from tests.reference import spectral as ref  # noqa: E402

CASES = (
    "camera-0/craquelure,camera-0/dust,camera-0/blobs,camera-1/thick,brick-0/text,"
    "gravel-0/blobs,grass-0/scratches,edges-0/structure,camera-1/texture"
)
LAST: dict = {}
RECORDS: list = []
TRUTH: dict = {}


def fit_block(values, weight, **options):
    """The reference's fit_block without its stopping tests (stop, floor, stall), keeping
    the model after each pick and each pick's gain and the residual E before it (LAST)."""
    LAST.update(hist=[], gains=[], energies=[])

    def record(gain, energy, model):
        LAST["hist"].append(model.copy())
        if gain is not None:
            LAST["gains"].append(gain)
            LAST["energies"].append(energy)

    options.update(stop=0.0, floor=0.0, stall=0.0, record=record)
    return ref.fit_block(values, weight, **options)


def hook(c, yc, xc, target):
    truth = TRUTH["crop"][c, yc[target], xc[target]]
    RECORDS.append(
        {
            "case": TRUTH["name"],
            "n": int(target.sum()),
            "err": np.array([((h[target] - truth) ** 2).sum() for h in LAST["hist"]]),
            "gains": np.array(LAST["gains"]),
            "energies": np.array(LAST["energies"]),
        }
    )


def recording_fill():
    """ref.fill with fit_block above and hook() after each block's channel: the reference's
    own source, two lines added, so that its plan and order stay the reference's."""
    src = inspect.getsource(ref.fill)
    fill_line = "work[c, yc[target], xc[target]] = model[target]"
    crop_line = "    part = out[:, y0:y1, x0:x1]\n"
    assert fill_line in src and crop_line in src
    src = src.replace(fill_line, fill_line + "\n" + " " * 20 + "hook(c, yc, xc, target)")
    src = src.replace(crop_line, crop_line + "    TRUTH['crop'] = TRUTH['full'][:, y0:y1, x0:x1]\n")
    space = dict(vars(ref), fit_block=fit_block, hook=hook, TRUTH=TRUTH)
    exec(src, space)  # noqa: S102 (the reference's own source)
    return space["fill"]


def stopped_at(r, test):
    g, e = r["gains"], r["energies"]
    return next((t for t in range(len(g)) if test(g, e, t)), len(g))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cases", default=CASES)
    args = parser.parse_args()
    from clpde.inpainting import spectral

    fill = recording_fill()
    cases = {c.name: c for c in corpus.build() if c.half == "calibration"}
    for name in args.cases.split(","):
        case = cases[name]
        if case.truth.ndim != 2 or case.kind != "uint8":
            raise SystemExit(f"{name}: grey 8-bit cases only")
        TRUTH.update(full=case.truth[None] / 255.0, name=name)
        border = 6 if spectral.thin(case.mask) else 12  # the thin border, as the fill's
        fill(TRUTH["full"], case.mask, border=border)
        print(f"{name}: {len(RECORDS)} block channels", file=sys.stderr, flush=True)
    rows = [r for r in RECORDS if r["n"] > 0]
    base = {r["case"]: 0.0 for r in rows}
    for r in rows:
        base[r["case"]] += r["err"][-1]
    total_picks = sum(len(r["gains"]) for r in rows)
    best = [int(np.argmin(r["err"])) for r in rows]
    print(f"{len(rows)} block channels; error least after picks (quartiles)", end=" ")
    print(np.quantile(best, [0.25, 0.5, 0.75]))
    tests = {f"gain < {s} E": lambda g, e, t, s=s: g[t] < s * e[t] for s in (0.005, 0.01, 0.02)}
    tests |= {f"E < {s} E0": lambda g, e, t, s=s: e[t] < s * e[0] for s in (0.01, 0.001)}
    tests |= {f"gain < {s} first": lambda g, e, t, s=s: g[t] < s * g[0] for s in (1e-3, 1e-4)}
    tests |= {f"{k} picks": lambda g, e, t, k=k: t >= k for k in (40, 60, 80)}
    for label, test in tests.items():
        err = {c: 0.0 for c in base}
        kept = 0
        for r in rows:
            t = stopped_at(r, test)
            err[r["case"]] += r["err"][min(t, len(r["err"]) - 1)]
            kept += t
        whole = 10 * np.log10(sum(base.values()) / sum(err.values()))
        per = ", ".join(f"{c} {10 * np.log10(base[c] / err[c]):+.3f}" for c in base)
        print(f"{label}: picks kept {kept / total_picks:.2f}, {whole:+.3f} dB; {per}")


if __name__ == "__main__":
    main()

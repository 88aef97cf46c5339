"""Results of the 2D tracker in each band storage, saved for a bitwise check across a
refactoring of the storage (tracking/storage.py). layout_bitwise.py covers the default
discrepancy in the three storages; this adds the others, the region and curvature terms,
and the brick-per-work-group launches, which a CPU takes only when forced.

    PYTHONPATH=<tree A> python benchmarks/track_storage_bitwise.py save out/tsbit/a
    PYTHONPATH=<tree B> python benchmarks/track_storage_bitwise.py save out/tsbit/b
    python benchmarks/track_storage_bitwise.py compare out/tsbit/a out/tsbit/b

Saved: the masks and level sets of `clpde.track` for each storage and discrepancy (ncc,
difference, huber; adaptive with a region and a curvature term), and, in each storage with
a work-group per brick, a LevelSet's values after a rebuild and a full reinitialisation.
"""

import warnings
from pathlib import Path

import numpy as np
from bitwise import main

STORAGES = ("lists", "bricks8x8", "bricks16x4")


def _sequence(n=48, frames=4, seed=1):
    rng = np.random.default_rng(seed)
    y, x = np.mgrid[:n, :n] + 0.0
    out = []
    for t in range(frames):
        inside = np.hypot(x - 18 - 1.5 * t, y - 22 - 0.5 * t) < 8 + 0.3 * t
        out.append((0.3 + 0.4 * inside + 0.05 * rng.normal(size=(n, n))).astype(np.float32))
    return np.stack(out), np.hypot(x - 18, y - 22) < 8


def save(out: Path) -> None:
    import clpde
    from clpde.runtime import get_runtime
    from clpde.tracking.levelset import LevelSet, signed_distance

    warnings.simplefilter("ignore")
    out.mkdir(parents=True, exist_ok=True)
    print("saving results of", clpde.__file__)
    frames, first = _sequence()
    cases = {
        "ncc": dict(discrepancy="ncc"),
        "difference": dict(discrepancy="difference"),
        "huber_edges": dict(discrepancy="huber", features="edges"),
        "adaptive_terms": dict(region_weight=1.0, curvature=0.2),
    }
    for storage in STORAGES:
        for tag, kw in cases.items():
            masks, phi = clpde.track(
                frames, first, storage=storage, progress=False, return_level_sets=True, **kw
            )
            np.save(out / f"track_{storage}_{tag}_masks.npy", np.asarray(masks))
            np.save(out / f"track_{storage}_{tag}_phi.npy", np.asarray(phi))
        u = signed_distance(first)
        ls = LevelSet(
            get_runtime(), u + 0.3, 3.0, np.float32, storage=storage, group_per_brick=True
        )
        ls.rebuild(5)
        np.save(out / f"levelset_{storage}_grouped_rebuild.npy", ls.values())
        ls.reinitialize()
        np.save(out / f"levelset_{storage}_grouped_reinit.npy", ls.values())


if __name__ == "__main__":
    main(save, __doc__)

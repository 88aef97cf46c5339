"""How motion='image''s and motion='checked''s settings were chosen: each candidate over
the calibration half of benchmarks/track_photo_corpus.py, mean IoU over its sequences (and
the worst frame).

    python benchmarks/track_image_search.py "[{'fo.HIDDEN_FLOOR': 0.6}, {}]"
    python benchmarks/track_image_search.py "[{'opt_curvature': 0.3}]" [half] [classes]
    python benchmarks/track_image_search.py "[{'opt_motion': 'checked', 'pr.CHECK_GAIN': 0.9}]"

A candidate sets module constants (ap.NAME: clpde.tracking.appearance, fo.NAME:
clpde.tracking.follow, mo.NAME: clpde.tracking.morph, pr.NAME: clpde.tracking.prediction)
or track options (opt_NAME); they stay set for the candidates after it in one run.
"""

from __future__ import annotations

import ast
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "benchmarks"))

from track_photo_corpus import corpus  # noqa: E402


def _iou(a, b):
    return (a & b).sum() / max((a | b).sum(), 1)


def main(argv=None):
    import clpde
    import clpde.tracking.appearance as ap
    import clpde.tracking.follow as fo
    import clpde.tracking.morph as mo
    import clpde.tracking.prediction as pr

    argv = sys.argv[1:] if argv is None else argv
    candidates = ast.literal_eval(argv[0]) if argv else [{}]
    half = argv[1] if len(argv) > 1 else "calibration"
    data = corpus(half, classes=argv[2].split(",")) if len(argv) > 2 else corpus(half)
    modules = {"ap": ap, "fo": fo, "mo": mo, "pr": pr}
    for candidate in candidates:
        options = {"motion": "image"}
        for key, value in candidate.items():
            if key.startswith("opt_"):
                options[key[4:]] = value
            else:
                module, name = key.split(".")
                setattr(modules[module], name, value)
        t0 = time.time()
        result = {}
        for name, (frames, truth, _cls) in data.items():
            masks = clpde.track(frames, truth[0], progress=False, **options)
            j = [_iou(a, b) for a, b in zip(masks[1:], truth[1:], strict=True)]
            result[name] = (min(j), float(np.mean(j)))
        print(
            candidate,
            f"mean {np.mean([v[1] for v in result.values()]):.3f}",
            f"worst {min(v[0] for v in result.values()):.3f}",
            f"{time.time() - t0:.0f}s",
            " ".join(f"{k}:{v[0]:.2f}/{v[1]:.2f}" for k, v in result.items()),
            flush=True,
        )


if __name__ == "__main__":
    main()

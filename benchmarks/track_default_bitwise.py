"""Results of the tracker's default (motion='image') and of motion='checked' on carphone and
on one sequence of each class of the photo corpus, saved for a bitwise check across a
change meant to make the default faster without changing what it returns.

    PYTHONPATH=<tree A> python benchmarks/track_default_bitwise.py save out/tdbit/a
    PYTHONPATH=<tree B> python benchmarks/track_default_bitwise.py save out/tdbit/b
    python benchmarks/track_default_bitwise.py compare out/tdbit/a out/tdbit/b

Saved: masks, level sets, discrepancy and confidence of `clpde.track` for carphone (colour
footage: default, checked and colour=True), carphone in grey (default), and seed 0 of each
photo corpus class (default). track_storage_bitwise.py covers the storages and the other
discrepancies.
"""

import warnings
from pathlib import Path

import numpy as np
from bitwise import main


def _cases():
    from track_photo_corpus import CLASSES, MAKERS
    from tracking import carphone

    frames, truth = carphone()
    grey = frames.astype(np.float64) @ np.array([0.299, 0.587, 0.114])
    yield "carphone_default", frames, truth[0], {}
    yield "carphone_checked", frames, truth[0], {"motion": "checked"}
    yield "carphone_colour_default", frames, truth[0], {"colour": True}
    yield "carphone_grey_default", grey, truth[0], {}
    for cls in CLASSES:
        f, masks = MAKERS[cls](0)
        yield f"photo_{cls}0_default", f, masks[0], {}


def save(out: Path) -> None:
    import clpde

    warnings.simplefilter("ignore")
    out.mkdir(parents=True, exist_ok=True)
    print("saving results of", clpde.__file__)
    for tag, frames, first, kw in _cases():
        masks, phi, disc, conf = clpde.track(
            frames,
            first,
            progress=False,
            return_level_sets=True,
            return_discrepancy=True,
            return_confidence=True,
            **kw,
        )
        for part, a in (("masks", masks), ("phi", phi), ("disc", disc), ("conf", conf)):
            np.save(out / f"{tag}_{part}.npy", np.asarray(a))
        print(tag, flush=True)


if __name__ == "__main__":
    main(save, __doc__)

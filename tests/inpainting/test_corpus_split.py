"""The benchmark corpus (tests/cases/inpaint_corpus.py): deterministic, split by source."""

import numpy as np
import pytest

from tests.cases import inpaint_corpus


@pytest.fixture(scope="module")
def corpus():
    return inpaint_corpus


def test_split_is_deterministic(corpus):
    a, b = corpus.build(), corpus.build()
    assert [c.name for c in a] == [c.name for c in b]
    for x, y in zip(a, b, strict=True):
        assert x.half == y.half and x.source == y.source
        assert np.array_equal(x.mask, y.mask)
        assert np.array_equal(x.truth, y.truth, equal_nan=True)


def test_split_is_disjoint_by_source(corpus):
    cases = corpus.build()
    halves = {}
    for c in cases:
        halves.setdefault(c.source, set()).add(c.half)
    assert all(len(h) == 1 for h in halves.values()), halves
    calibration = {s for s, h in halves.items() if h == {"calibration"}}
    assert set(corpus.CALIBRATION_PHOTOS) <= calibration
    images = {c.name.split("/")[0] for c in cases}
    assert len(images) >= 30
    # every class is on both sides, so a choice calibrated on one half is tested on the other
    for d in corpus.CLASSES:
        assert {c.half for c in cases if c.damage == d} == {"calibration", "test"}, d


def test_sixteen_bit_content_is_not_widened_8_bit(corpus):
    cases = corpus.build()
    wide = [c for c in cases if c.kind == "uint16"]
    assert wide and all(corpus.sixteen_bit_content(c.truth) > 0.9 for c in wide)
    widened = (np.arange(256, dtype=np.uint16) * 257).reshape(16, 16)
    assert corpus.sixteen_bit_content(widened) == 0


def test_scores(corpus):
    case = next(c for c in corpus.build() if c.kind == "float")
    assert corpus.psnr(case, case.truth) == corpus.CAP
    off = case.truth + np.where(case.mask, 0.1 * case.peak, 0).astype(case.truth.dtype)
    assert corpus.psnr(case, off) == pytest.approx(20.0, abs=1e-3)

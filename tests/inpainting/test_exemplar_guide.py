"""The exemplar's structure guide: which coherence fill it uses (exemplar._guide_params)."""

import numpy as np

from clpde.inpainting import coherence, exemplar


def test_deep_holes_get_the_stronger_pull_and_thin_ones_the_fill_defaults():
    deep = np.zeros((80, 80), bool)
    deep[20:60, 20:60] = True  # 20 px from the border at its centre
    stroke = np.zeros((80, 80), bool)
    stroke[30:36, 5:75] = True  # a text stroke or a scratch: 3 px deep
    assert exemplar._guide_params(deep) == {"kappa": exemplar.GUIDE_KAPPA}
    assert exemplar._guide_params(stroke) == {}
    assert exemplar.GUIDE_KAPPA > coherence.DEFAULTS["kappa"]

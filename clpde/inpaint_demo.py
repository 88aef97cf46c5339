"""Deprecated alias, kept for one release: the damaged photo is `clpde.data.damaged_astronaut`
(and `clpde.data.damage_mask`), the demonstration run is in `clpde.cli._inpaint_demo`."""

import warnings

from .cli._inpaint_demo import peer_psnr, psnr_in_mask, run_demo, side_by_side  # noqa: F401
from .data import damage_mask  # noqa: F401
from .data import damaged_astronaut as demo_case  # noqa: F401

warnings.warn("clpde.inpaint_demo is deprecated: use clpde.data.damaged_astronaut and "
              "clpde.data.damage_mask", DeprecationWarning, stacklevel=2)

"""method="transport": the thesis's scheme (chapter 3), run by clpde.inpaint.LevelSolver."""

from __future__ import annotations

import numpy as np

from . import multiresolution as mr
from .api import GHOST, InpaintParams, TransportRun

DESCRIPTION = ("transport of smoothness along the isophotes, interleaved with anisotropic "
               "diffusion (thesis ch. 3)")
SOFT_MASK = True


def _levels(omega, levels):

    return levels if levels is not None else mr.auto_levels(omega)


def _reach(params) -> int:
    """Pixels outside Omega that one level reads: the band Omega-epsilon plus the diffusion
    stencil, the pre-smoothing's reach, the transport's two-cell stencil and the
    biharmonic start's two cells."""

    p = InpaintParams(**{k: v for k,
                         v in params.items() if k in InpaintParams.__dataclass_fields__})
    return int(np.ceil(p.epsilon)) + 1 + p.presmooth + GHOST + 2


def ALIGN(omega, levels=None, **params) -> int:
    """Boxes start on multiples of 2**(levels - 1), so that their pyramids coincide with
    the whole image's."""
    return 2 ** (_levels(omega, levels) - 1)


def MARGIN(omega, levels=None, **params) -> int:
    scale = 2 ** (_levels(omega, levels) - 1)
    return _reach(params) * scale + scale


def solve(data, omega, runtime, *, dtype=np.float32, progress=None, seed=None, fidelity=None,
          levels=None, **params):

    run = TransportRun(runtime, data, omega, params, levels=levels, dtype=dtype,
                       progress=progress, fidelity=fidelity)
    for _ in run.states():
        pass
    return run.solution

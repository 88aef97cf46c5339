"""Deprecated alias, kept for one release: the demonstration data is in `clpde.data`
(surface_shape, checker, colour_pattern, surface_noise), the ready-made runs in
`clpde.cli.surface` (load_surface, run_flow, write_run)."""

import warnings

from ..cli.surface import (  # noqa: F401
    DATA_FLOWS,
    FLOWS,
    SurfaceRun,
    encloses_volume,
    load_surface,
    mesh_colours,
    run_flow,
    tv_time,
    write_run,
)
from ..cli.surface import write_png as _write_png  # noqa: F401
from ..data import SURFACE_SHAPES as SHAPES  # noqa: F401
from ..data import checker, colour_pattern, surface_noise  # noqa: F401

warnings.warn("clpde.surface.demo is deprecated: use clpde.data and clpde.cli.surface",
              DeprecationWarning, stacklevel=2)

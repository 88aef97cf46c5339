"""Deprecated alias, kept for one release: the toy scenes are `clpde.data.region_scene`, the
runs of a scene and their outputs are in `clpde.cli.regions`."""

import warnings

from .cli.regions import (  # noqa: F401
    FLOWS,
    MAX_COLOUR_REGIONS,
    colour_labels,
    curvature_sign_regions,
    displacement,
    mesh_scene,
    run_scene,
    write_frames,
)
from .data import REGION_SCENES as SCENES  # noqa: F401
from .data import RegionScene as Scene  # noqa: F401
from .data import _axes  # noqa: F401
from .data import _capsule as capsule  # noqa: F401
from .data import _two_spheres as two_spheres  # noqa: F401
from .data import region_scene as toy_scene  # noqa: F401

warnings.warn("clpde.regions_demo is deprecated: use clpde.data.region_scene and "
              "clpde.cli.regions (run_scene, write_frames)", DeprecationWarning, stacklevel=2)

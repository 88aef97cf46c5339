"""Regions tracked on deforming surfaces (thesis section 2.2): the tracker, its brick storage
and the region meshes."""

from .api import region_tracker, track_region
from .tracker import RegionTracker

__all__ = ["RegionTracker", "region_tracker", "track_region"]

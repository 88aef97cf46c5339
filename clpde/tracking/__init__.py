"""Contour tracking through image sequences: the morphing level set (thesis chapter 2), its
level-set storage, and the local features and motion it follows. Every option and its
default lives in `TrackOptions`."""

from .contours import MorphingTracker, track
from .options import TrackOptions

__all__ = ["MorphingTracker", "TrackOptions", "track"]

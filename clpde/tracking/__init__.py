"""Contour tracking through image sequences: the morphing level set (thesis chapter 2), its
level-set storage, and the local features and motion it follows. Every option and its
default lives in `TrackOptions`."""

from .options import TrackOptions
from .tracker import MorphingTracker, track

__all__ = ["MorphingTracker", "TrackOptions", "track"]

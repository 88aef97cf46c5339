"""Contour tracking through image sequences: the morphing level set (thesis chapter 2), its
level-set storage, and the local features and motion it follows."""

from .contours import MorphingTracker, track

__all__ = ["MorphingTracker", "track"]

"""Dense motion: optical flow on the device, coarse to fine, and backward warping.

Film restoration and tracking both use it. See `optical_flow` for the flow's convention.
"""

from .flow import FlowParams, FlowSolver, optical_flow, warp

__all__ = ["FlowParams", "FlowSolver", "optical_flow", "warp"]

"""Flows on the image plane: linear and nonlinear diffusion, curvature flows, TV (ROF)
denoising, and the same runs in tiles for images larger than the device's memory."""

from .flows import FLOWS, PlanarFlow, diffuse, stability_limit
from .rof import denoise_tv

__all__ = ["FLOWS", "PlanarFlow", "denoise_tv", "diffuse", "stability_limit"]

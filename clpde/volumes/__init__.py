"""3D volumes: TV denoising, diffusion and harmonic inpainting of (Z, Y, X[, C]) arrays with
voxel spacing (kernels/volumes/volume.cl). `clpde.denoise_tv` and `clpde.diffuse` send
volumes here; inpainting a volume is `inpaint_volume` (a (Z, Y, X) array is ambiguous with a
colour image in `clpde.inpaint`)."""

from .inpaint import inpaint_volume

__all__ = ["inpaint_volume"]

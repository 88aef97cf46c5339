"""Files in and out: images (images.py), 3D volumes (volumes.py: NIfTI and multi-page TIFF),
frame sequences (frames.py), and video (video.py, with the audio and subtitle streams that
travel with it in side_streams.py; needs PyAV). Every writer writes atomically; readers keep
the file's dtype."""

from .images import read_image, read_mask, write_gif, write_image
from .volumes import VolumeInfo, is_volume_file, read_volume, write_volume

__all__ = [
    "VolumeInfo",
    "is_volume_file",
    "read_image",
    "read_mask",
    "read_volume",
    "write_gif",
    "write_image",
    "write_volume",
]

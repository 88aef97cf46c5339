"""Files in and out: images (images.py), frame sequences (frames.py), and video (video.py,
with the audio and subtitle streams that travel with it in side_streams.py; needs PyAV).
Every writer writes atomically; readers keep the file's dtype."""

from .images import read_image, read_mask, write_gif, write_image

__all__ = ["read_image", "read_mask", "write_gif", "write_image"]

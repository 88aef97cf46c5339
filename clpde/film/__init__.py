"""Film restoration: finding dirt and scratches, and filling them from neighbouring frames.

`detect_defects` finds blotches and line scratches (temporal cues for films, spatial cues
for a single scanned photograph); `inpaint_video` fills given masks from the motion-
compensated neighbouring frames, with spatial inpainting where they do not help.
"""

from .detect import BLOTCH, CLEAN, SCRATCH, detect_defects
from .fill import inpaint_video

__all__ = ["BLOTCH", "CLEAN", "SCRATCH", "detect_defects", "inpaint_video"]

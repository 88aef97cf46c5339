"""clpde in napari: inpaint painted damage, denoise, carry labels through slices and frames,
restore films, run flows on meshes; every run in a worker thread that can be cancelled.

Install with ``pip install "clpde[napari]"``; napari finds the plugin through its npe2
manifest (``napari.yaml`` beside this file). The widgets are plain classes taking the
viewer, so they also work in a script: ``InpaintWidget(viewer)``.
"""

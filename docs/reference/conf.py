"""Sphinx configuration of clpde's API reference (built by .ci/run with warnings as errors:
python -m sphinx -W -b html docs/reference build/reference)."""

import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))  # the checkout's clpde, as the tests import it
sys.path.insert(0, str(Path(__file__).resolve().parent))  # generate.py

project = "clpde"
extensions = ["sphinx.ext.autodoc", "numpydoc", "generate"]
# autodoc documents each class's methods in full (generate.py asks for :members:, the
# surface's flows being ImplicitSurface's methods); numpydoc's summary tables would repeat them.
numpydoc_show_class_members = False
autodoc_default_options = {"members": False}
autodoc_typehints = "none"  # the numpydoc Parameters sections give the types
html_theme = "alabaster"
exclude_patterns = ["_build"]

"""clpde's OpenCL C sources, installed as the package ``clpde.kernels`` (pyproject.toml maps
this folder there; in a source checkout the link clpde/kernels points here). clpde.runtime
finds them through importlib.resources. One folder per capability, as clpde/ has; shared
code is in headers (.h), kernels in .cl files."""

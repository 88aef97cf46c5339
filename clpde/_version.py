"""clpde's version, in one place (the package and the batch manifest read it)."""

__version__ = "0.1.0"

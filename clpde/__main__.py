"""`python -m clpde` runs the command line."""

from .cli import run

run()

"""`import clpde` loads no capability: each public name loads its module on first use."""

import subprocess
import sys

import clpde


def test_import_loads_no_capability_and_every_public_name_resolves():
    code = (
        "import sys, clpde\n"
        "heavy = [m for m in ('clpde.film', 'clpde.surface', 'clpde.tracking', 'scipy', "
        "'trimesh', 'pyopencl') if m in sys.modules]\n"
        "print(heavy)\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"
    for name in clpde.__all__:
        assert getattr(clpde, name) is not None
    assert clpde.surface.ImplicitSurface is not None

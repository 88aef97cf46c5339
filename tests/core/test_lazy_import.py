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


def test_help_loads_no_subcommand_module():
    """`clpde --help` lists the subcommands from clpde.cli.SUBCOMMANDS alone: no capability,
    numpy or pyopencl is imported for it."""
    code = (
        "import sys\n"
        "from clpde.cli import main\n"
        "assert main(['--help']) == 0\n"
        "print([m for m in sys.modules if m.startswith('clpde.cli.') and m != 'clpde.cli._parser'"
        " or m in ('numpy', 'pyopencl')])\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip().splitlines()[-1] == "[]"

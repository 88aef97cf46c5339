"""The package's layout keeps its rules: arrows point down (no import cycles, counting imports
inside functions, between files and between folders; only ``clpde/__main__.py`` imports the
command line; the ground floor imports no capability), a small ground floor,
and no module or function too long to read. Measured by tests/cases/layout_metrics.py."""

import re
from pathlib import Path

import pytest

from tests.cases import layout_metrics

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def metrics():
    return layout_metrics


def test_the_counter_sees_imports_inside_functions(metrics, tmp_path):
    package = tmp_path / "clpde"
    (package / "sub").mkdir(parents=True)
    (package / "__init__.py").write_text("")
    (package / "a.py").write_text("def f():\n    from .sub import b\n")
    (package / "c.py").write_text(
        "from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n    from . import a\n"
    )
    (package / "sub" / "__init__.py").write_text("from . import b\n")
    (package / "sub" / "b.py").write_text("from .. import a, c\n")
    assert metrics.cycles(metrics.imports(tmp_path)) == [["clpde.a", "clpde.sub.b"]]


def test_no_import_cycles(metrics):
    assert metrics.cycles(metrics.imports(ROOT)) == []


# Package-level cycles that stay, each with its reason (none: film takes its Dask cluster
# from the caller, so film <-> scale went; data <-> surface went with surface/shapes.py).
KNOWN_PACKAGE_CYCLES: list[list[str]] = []


def test_the_package_level_check_sees_a_cycle_between_folders(metrics, tmp_path):
    package = tmp_path / "clpde"
    for folder in ("a", "b"):
        (package / folder).mkdir(parents=True)
        (package / folder / "__init__.py").write_text("")
    (package / "__init__.py").write_text("")
    (package / "a" / "x.py").write_text("from ..b import y\n")
    (package / "b" / "y.py").write_text("")
    (package / "b" / "z.py").write_text("from ..a import w\n")
    (package / "a" / "w.py").write_text("")
    edges = metrics.imports(tmp_path)
    assert metrics.cycles(edges) == []
    assert metrics.cycles(metrics.package_imports(edges)) == [["clpde.a", "clpde.b"]]


def test_no_package_level_cycles_but_the_known_ones(metrics):
    assert metrics.measure(ROOT)["package_cycles"] == KNOWN_PACKAGE_CYCLES


def test_ground_floor_imports_no_capability_and_loads_none_of_its_kernels(metrics):
    assert metrics.measure(ROOT)["ground_floor_reaching_up"] == []


def test_only_main_imports_the_command_line(metrics):
    assert metrics.measure(ROOT)["library_modules_importing_cli"] == []


def test_imports_inside_functions_are_for_optional_dependencies_only(metrics):
    """An import of a clpde module inside a function would only hide a cycle."""
    assert metrics.measure(ROOT)["function_level_clpde_import_list"] == []


def test_ground_floor_is_small(metrics):
    top = metrics.measure(ROOT)["top_level_modules"]
    assert len(top) <= metrics.MAX_TOP_LEVEL, top


def test_no_module_over_600_lines(metrics):
    assert metrics.measure(ROOT)["modules_over_600_lines"] == []


def test_no_function_over_100_lines_of_code(metrics):
    """Docstrings, comments and blank lines not counted."""
    assert metrics.long_functions(ROOT) == []


def test_no_deprecation_shims(metrics):
    assert metrics.shims(ROOT) == []


# a path joined onto benchmarks/ (for sys.path or a spec) or an import of it
BENCHMARKS_PATH = re.compile(r"""/ ["']benchmarks["']|^\s*(from|import) benchmarks\b""")


def test_tests_do_not_import_benchmarks():
    """Cases both use are in tests/cases/; a test that reached into benchmarks/ would break
    with any benchmark's edit, and run its module-level set-up."""
    reaching = [
        f"{path.relative_to(ROOT)}:{number}"
        for path in sorted((ROOT / "tests").rglob("*.py"))
        for number, line in enumerate(path.read_text().splitlines(), 1)
        if BENCHMARKS_PATH.search(line)
    ]
    assert reaching == []

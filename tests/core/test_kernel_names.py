"""Every kernel that the host code asks for by name exists in the kernel file it names.

A kernel is looked up by strings (`runtime.kernel("inpainting/transport.cl",
"transport_step")`), so a renamed or removed kernel would only fail when that code path
runs; this test reads the sources instead and fails at once.
"""

import ast
import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
KERNEL_DIR = ROOT / "kernels"

# kernel("file.cl", "name" ...), new_kernel(...), program("file.cl" ...); and any lookup that
# names no file first (a kernel name alone, or a variable), which the one signature forbids
WITH_FILE = re.compile(r"""kernel\(\s*["']([\w/]+\.cl)["']\s*,\s*["'](\w+)["']""")
# a table's ("file.cl", "name") pairs, looked up through a variable (flows.STEP_KERNELS)
PAIR = re.compile(r"""\(\s*["']([\w/]+\.cl)["']\s*,\s*["'](\w+)["']\s*\)""")
FILE_NAMED = re.compile(r"""(?:kernel|program)\(\s*["']([\w/]+\.cl)["']""")
NOT_LITERAL = re.compile(
    r"""\.(?:new_)?kernel\("""
    r"""(?!\s*["'][\w/]+\.cl["']\s*,\s*["']\w+["'])(?!\s*filename\b)"""
)
DEFINED = re.compile(r"__kernel\s+(?:__attribute__\s*\(\(.*?\)\)\s*)?void\s+(\w+)", re.S)
INCLUDE = re.compile(r'#include\s+"([\w./]+)"')


def _kernels_in(filename: str, seen=None) -> set[str]:
    """Kernel names defined in a file and the files it includes."""
    seen = set() if seen is None else seen
    if filename in seen:
        return set()
    seen.add(filename)
    # the runtime's include path: kernels/, then kernels/common/
    path = KERNEL_DIR / filename
    if not path.is_file():
        path = KERNEL_DIR / "common" / filename
    text = path.read_text()
    names = set(DEFINED.findall(text))
    for included in INCLUDE.findall(text):
        names |= _kernels_in(included, seen)
    return names


def _host_sources():
    for path in sorted((ROOT / "clpde").rglob("*.py")):
        yield path, path.read_text()


def test_every_named_kernel_exists_in_its_file():
    missing = []
    checked = 0
    for path, text in _host_sources():
        for filename, name in WITH_FILE.findall(text) + PAIR.findall(text):
            checked += 1
            if not (KERNEL_DIR / filename).is_file():
                missing.append(f"{path.name}: kernel file {filename} does not exist")
            elif name not in _kernels_in(filename):
                missing.append(f"{path.name}: {name} is not a kernel of {filename}")
    assert checked > 20, "the pattern no longer finds the host code's kernel lookups"
    assert not missing, "\n".join(missing)


def test_every_lookup_names_its_file_and_kernel_as_literals():
    """`g.kernel("surface/heat.cl", "heat_step")`: grepping a kernel's name lands on its lookups."""
    loose = [
        f"{path.relative_to(ROOT)}:{text.count(chr(10), 0, m.start()) + 1}"
        for path, text in _host_sources()
        for m in NOT_LITERAL.finditer(text)
    ]
    assert not loose, "kernel lookups without a literal file and kernel name:\n" + "\n".join(loose)


def _declared_files(text: str):
    for node in ast.parse(text).body:
        if isinstance(node, ast.Assign) and any(
            isinstance(t, ast.Name) and t.id == "KERNEL_FILES" for t in node.targets
        ):
            return set(ast.literal_eval(node.value))
    return None


def test_each_module_declares_the_kernel_files_it_uses():
    wrong = []
    for path, text in _host_sources():
        used = set(FILE_NAMED.findall(text)) | {f for f, _ in PAIR.findall(text)}
        if not used:
            continue
        declared = _declared_files(text)
        if declared != used:
            wrong.append(
                f"{path.relative_to(ROOT)}: KERNEL_FILES = {sorted(declared or ())}, "
                f"its lookups name {sorted(used)}"
            )
    assert not wrong, "\n".join(wrong)


def test_every_kernel_is_named_after_its_file():
    """The naming rule `<file>_<verb>`: `planar_heat_step` is in planar.cl, and no two files
    define the same kernel name, so a name in a profile or a log leads to one file."""
    wrong, owner = [], {}
    for path in sorted(KERNEL_DIR.rglob("*.cl")):
        for name in DEFINED.findall(path.read_text()):
            rel = path.relative_to(KERNEL_DIR).as_posix()
            if not name.startswith(path.stem + "_"):
                wrong.append(f"{rel}: {name} does not start with {path.stem}_")
            if name in owner:
                wrong.append(f"{rel}: {name} is also defined in {owner[name]}")
            owner[name] = rel
    assert len(owner) > 100, "the pattern no longer finds the kernels"
    assert not wrong, "\n".join(wrong)

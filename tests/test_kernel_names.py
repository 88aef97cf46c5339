"""Every kernel that the host code asks for by name exists in the kernel file it names.

A kernel is looked up by strings (`runtime.kernel("inpaint.cl", "transport_step")`), so a
renamed or removed kernel would only fail when that code path runs; this test reads the
sources instead and fails at once.
"""

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
KERNEL_DIR = ROOT / "kernels"

# kernel("file.cl", "name" ...) and kernel("name" ...) (Grid3D.kernel, wired to surface.cl)
WITH_FILE = re.compile(r"""kernel\(\s*["'](\w+\.cl)["']\s*,\s*["'](\w+)["']""")
NAME_ONLY = re.compile(r"""\.kernel\(\s*["'](\w+)["']\s*[,)]""")
DEFINED = re.compile(r"__kernel\s+(?:__attribute__\s*\(\(.*?\)\)\s*)?void\s+(\w+)", re.S)
INCLUDE = re.compile(r'#include\s+"([\w.]+)"')


def _kernels_in(filename: str, seen=None) -> set[str]:
    """Kernel names defined in a file and the files it includes."""
    seen = set() if seen is None else seen
    if filename in seen:
        return set()
    seen.add(filename)
    text = (KERNEL_DIR / filename).read_text()
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
        for filename, name in WITH_FILE.findall(text):
            checked += 1
            if not (KERNEL_DIR / filename).is_file():
                missing.append(f"{path.name}: kernel file {filename} does not exist")
            elif name not in _kernels_in(filename):
                missing.append(f"{path.name}: {name} is not a kernel of {filename}")
    assert checked > 20, "the pattern no longer finds the host code's kernel lookups"
    assert not missing, "\n".join(missing)


def test_kernels_named_without_a_file_exist_somewhere():
    every = set()
    for cl_file in KERNEL_DIR.glob("*.cl"):
        every |= _kernels_in(cl_file.name)
    missing = [f"{path.name}: {name}" for path, text in _host_sources()
               for name in NAME_ONLY.findall(text) if not name.endswith(".cl") and name not in every]
    assert not missing, "kernels named in the host code but defined nowhere:\n" + "\n".join(missing)

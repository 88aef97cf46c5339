"""Pages written at build time, so that the reference cannot drift from the code:

- one page per public namespace (``clpde``, ``clpde.io``, ``clpde.surface``,
  ``clpde.data``, ``clpde.inpainting``, ``clpde.tracking``, ``clpde.volumes``), an entry
  for every name in its ``__all__``, classes with their documented methods;
- a gallery page per script in examples/: its docstring, the pictures it makes (those it
  names under docs/images/) and its source. Nothing is run.
"""

import ast
import importlib
import inspect
import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
NAMESPACES = [
    ("clpde", "Top level: clpde"),
    ("clpde.inpainting", "Inpainting methods: clpde.inpainting"),
    ("clpde.io", "Files in and out: clpde.io"),
    ("clpde.surface", "PDEs on implicit surfaces: clpde.surface"),
    ("clpde.data", "Test images and scenes: clpde.data"),
    ("clpde.tracking", "Tracking options: clpde.tracking"),
    ("clpde.volumes", "3D volumes: clpde.volumes"),
]


def _heading(text: str, mark: str = "=") -> list[str]:
    return [text, mark * len(text), ""]


def _directive(obj) -> str:
    if inspect.ismodule(obj):
        return ""
    if inspect.isclass(obj):
        return "autoexception" if issubclass(obj, BaseException) else "autoclass"
    return "autofunction" if callable(obj) else "autodata"


def _namespace_page(module_name: str, title: str) -> str:
    module = importlib.import_module(module_name)
    lines = [
        *_heading(title),
        f".. automodule:: {module_name}",
        "",
        f".. currentmodule:: {module_name}",
        "",
    ]
    top = importlib.import_module("clpde")
    for name in sorted(module.__all__, key=str.lower):
        obj = getattr(module, name)
        directive = _directive(obj)
        if directive:  # submodules have pages of their own
            lines += [f".. {directive}:: {name}"]
            if directive == "autoclass":
                # the methods in full: ImplicitSurface's are the surface flows' only public
                # form, some from its base class (surface/flow_methods.py)
                lines += ["   :members:", "   :inherited-members:"]
            if module is not top and getattr(top, name, None) is obj:
                lines += ["   :no-index:"]  # indexed on the top-level page
            lines += [""]
    return "\n".join(lines)


def _pictures(source: str) -> list[str]:
    names = re.findall(r"[\"']([\w.-]+\.(?:png|gif))[\"']", source)
    return [n for n in dict.fromkeys(names) if (ROOT / "docs" / "images" / n).exists()]


def _gallery_page(script: Path) -> str:
    source = script.read_text()
    doc = ast.get_docstring(ast.parse(source)) or ""
    lines = [*_heading(script.stem), doc, ""]
    for picture in _pictures(source):
        lines += [f".. image:: ../../images/{picture}", ""]
    lines += [f".. literalinclude:: ../../../examples/{script.name}", "   :language: python", ""]
    return "\n".join(lines)


def _write(path: Path, text: str) -> None:
    if not path.exists() or path.read_text() != text:  # unchanged pages are not reread
        path.write_text(text)


def _write_pages(app) -> None:
    source = Path(app.srcdir)
    for module_name, title in NAMESPACES:
        _write(source / f"{module_name.replace('.', '_')}.rst", _namespace_page(module_name, title))
    (source / "gallery").mkdir(exist_ok=True)
    entries = []
    for script in sorted((ROOT / "examples").glob("[!_]*.py")):
        _write(source / "gallery" / f"{script.stem}.rst", _gallery_page(script))
        entries.append(f"   gallery/{script.stem}")
    index = [*_heading("Gallery"), ".. toctree::", "   :maxdepth: 1", "", *entries, ""]
    _write(source / "gallery.rst", "\n".join(index))


def _escape_bars(app, what, name, obj, options, lines) -> None:
    """Docstrings write norms as |grad u|, plain text for a terminal's help(); to
    reStructuredText a bar opens a substitution, so escape them before numpydoc reads."""
    lines[:] = [line.replace("|", "\\|") for line in lines]


def setup(app):
    app.connect("builder-inited", _write_pages)
    app.connect("autodoc-process-docstring", _escape_bars, priority=100)
    return {"parallel_read_safe": True}

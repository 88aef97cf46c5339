"""How clpde's package is laid out, measured from its source: import cycles, top-level modules,
long modules and functions, deprecation shims.

    python tests/cases/layout_metrics.py [--root PATH] [--json OUT]

Every import statement that can run counts, wherever it sits (module level, inside functions):
only imports under ``if TYPE_CHECKING:`` are left out, since they never run (they name types
for annotations); they are counted apart. An import of ``clpde.a.b`` is an edge to module
``clpde.a.b`` and, for ``from clpde.a import b``, to ``clpde.a.b`` when that is a module, else
to ``clpde.a``'s ``__init__``. A cycle is a strongly connected component of that graph with
more than one module (or a module importing itself). tests/core/test_layout.py asserts the
targets on these numbers.
"""

from __future__ import annotations

import argparse
import ast
import json
import sys
from pathlib import Path

MAX_TOP_LEVEL = 10
MAX_MODULE_LINES = 600
MAX_FUNCTION_LINES = 100


def modules(root: Path) -> dict[str, Path]:
    """Dotted name -> file for every module of the package under root/clpde."""
    found = {}
    for path in sorted((root / "clpde").rglob("*.py")):
        parts = list(path.relative_to(root).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts = parts[:-1]
        found[".".join(parts)] = path
    return found


def _resolve(module: str, is_package: bool, node: ast.ImportFrom) -> str:
    if not node.level:
        return node.module or ""
    base = module.split(".")
    if not is_package:
        base = base[:-1]
    base = base[: len(base) - (node.level - 1)]
    return ".".join(base + ([node.module] if node.module else []))


def _type_checking(node: ast.AST) -> bool:
    test = getattr(node, "test", None) if isinstance(node, ast.If) else None
    return (isinstance(test, ast.Name) and test.id == "TYPE_CHECKING") or (
        isinstance(test, ast.Attribute) and test.attr == "TYPE_CHECKING"
    )


def _walk(node: ast.AST, in_function: bool = False, prefix: str = "", typing: bool = False):
    """(node, inside a function?, qualified name of the enclosing def) for every node; with
    typing=True only the nodes under ``if TYPE_CHECKING:``, else all others."""
    for child in ast.iter_child_nodes(node):
        if _type_checking(child) and not typing:
            continue
        inner = in_function or isinstance(
            child, ast.FunctionDef | ast.AsyncFunctionDef | ast.Lambda
        )
        name = prefix
        if isinstance(child, ast.FunctionDef | ast.AsyncFunctionDef | ast.ClassDef):
            name = f"{prefix}.{child.name}"
        if typing and _type_checking(child):
            yield from _walk(child, inner, name, typing=False)
            continue
        if not typing:
            yield child, inner, name
        yield from _walk(child, inner, name, typing)


def imports(root: Path, typing: bool = False) -> dict[str, list[tuple[str, bool, int]]]:
    """Module -> [(imported clpde module, inside a function?, line)]; typing=True: the
    imports under ``if TYPE_CHECKING:`` instead."""
    mods = modules(root)
    edges: dict[str, list[tuple[str, bool, int]]] = {}
    for name, path in mods.items():
        is_package = path.name == "__init__.py"
        found = []
        for node, inner, _ in _walk(ast.parse(path.read_text(), str(path)), typing=typing):
            if isinstance(node, ast.Import):
                for alias in node.names:
                    if alias.name.split(".")[0] == "clpde":
                        target = alias.name
                        while target not in mods and "." in target:
                            target = target.rsplit(".", 1)[0]
                        found.append((target, inner, node.lineno))
            elif isinstance(node, ast.ImportFrom):
                base = _resolve(name, is_package, node)
                if base.split(".")[0] != "clpde":
                    continue
                for alias in node.names:
                    target = f"{base}.{alias.name}"
                    found.append((target if target in mods else base, inner, node.lineno))
        edges[name] = [e for e in found if e[0] in mods]
    return edges


def cycles(edges: dict[str, list[tuple[str, bool, int]]]) -> list[list[str]]:
    """The import graph's strongly connected components with more than one module, or with
    a self-import (Tarjan's algorithm, iterative)."""
    graph = {m: sorted({t for t, _, _ in es}) for m, es in edges.items()}
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    on_stack: set[str] = set()
    stack: list[str] = []
    out = []
    counter = 0
    for start in graph:
        if start in index:
            continue
        work = [(start, iter(graph[start]))]
        index[start] = low[start] = counter
        counter += 1
        stack.append(start)
        on_stack.add(start)
        while work:
            node, it = work[-1]
            advanced = False
            for nxt in it:
                if nxt not in index:
                    index[nxt] = low[nxt] = counter
                    counter += 1
                    stack.append(nxt)
                    on_stack.add(nxt)
                    work.append((nxt, iter(graph.get(nxt, []))))
                    advanced = True
                    break
                if nxt in on_stack:
                    low[node] = min(low[node], index[nxt])
            if advanced:
                continue
            work.pop()
            if work:
                low[work[-1][0]] = min(low[work[-1][0]], low[node])
            if low[node] == index[node]:
                component = []
                while True:
                    top = stack.pop()
                    on_stack.discard(top)
                    component.append(top)
                    if top == node:
                        break
                if len(component) > 1 or node in graph.get(node, []):
                    out.append(sorted(component))
    return sorted(out)


def unit(module: str) -> str:
    """The package-level unit of a module: its capability's folder (clpde.surface for
    clpde.surface.flows), or the ground-floor module itself (clpde.fields)."""
    return ".".join(module.split(".")[:2])


def package_imports(edges: dict[str, list[tuple[str, bool, int]]]):
    """The import graph between units (see `unit`), in `imports`' form, for `cycles`: two
    folders importing each other through different files are a cycle here, which the
    file-level graph cannot see. The package's own __init__ (the lazy public API) is left
    out: every unit is below it."""
    out: dict[str, list[tuple[str, bool, int]]] = {}
    for module, es in edges.items():
        if module == "clpde":
            continue
        found = out.setdefault(unit(module), [])
        found += [(unit(t), f, line) for t, f, line in es if unit(t) not in (unit(module), "clpde")]
    return out


# The ground floor: the top-level modules, and clpde._device (runtime's pyopencl helpers);
# its kernels are in these folders of kernels/
GROUND_FLOOR_PACKAGES = ("clpde._device",)
GROUND_FLOOR_KERNELS = ("common", "bricks")


def ground_floor(root: Path) -> list[str]:
    mods = modules(root)
    return sorted(
        m
        for m, p in mods.items()
        if (m.count(".") == 1 and p.name not in ("__init__.py", "__main__.py"))
        or m in GROUND_FLOOR_PACKAGES
    )


def ground_floor_reaching_up(root: Path) -> list[str]:
    """'module -> capability' for each import of a capability by the ground floor, and
    'module: kernels/FILE' for each kernel file a ground-floor module declares outside the
    ground floor's kernel folders (its KERNEL_FILES)."""
    floor = set(ground_floor(root))
    mods = modules(root)
    out = [
        f"{m} -> {t}"
        for m, es in imports(root).items()
        if m in floor
        for t, _, _ in es
        if unit(t) not in floor
    ]
    for m in sorted(floor):
        for node in ast.parse(mods[m].read_text()).body:
            if isinstance(node, ast.Assign) and any(
                isinstance(t, ast.Name) and t.id == "KERNEL_FILES" for t in node.targets
            ):
                out += [
                    f"{m}: kernels/{f}"
                    for f in ast.literal_eval(node.value)
                    if f.split("/")[0] not in GROUND_FLOOR_KERNELS
                ]
    return sorted(set(out))


def code_lines(node: ast.AST, lines: list[str]) -> int:
    """Lines of code of a function: not blank, not comment-only, not its docstring."""
    skip = set()
    body = getattr(node, "body", [])
    if (
        body
        and isinstance(body[0], ast.Expr)
        and isinstance(body[0].value, ast.Constant)
        and isinstance(body[0].value.value, str)
    ):
        skip = set(range(body[0].lineno, body[0].end_lineno + 1))
    start = min([node.lineno] + [d.lineno for d in getattr(node, "decorator_list", [])])
    count = 0
    for number in range(start, node.end_lineno + 1):
        text = lines[number - 1].strip()
        if number in skip or not text or text.startswith("#"):
            continue
        count += 1
    return count


def long_functions(root: Path, limit: int = MAX_FUNCTION_LINES) -> list[tuple[str, int]]:
    out = []
    for name, path in modules(root).items():
        source = path.read_text()
        lines = source.splitlines()
        for node, _, qual in _walk(ast.parse(source), prefix=name):
            if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef):
                n = code_lines(node, lines)
                if n > limit:
                    out.append((qual, n))
    return sorted(out, key=lambda item: -item[1])


def shims(root: Path) -> list[str]:
    """Deprecation shims: DeprecationWarnings raised, deprecated-alias decorators and
    renamed-keyword helpers used, and alias modules."""
    out = []
    for name, path in modules(root).items():
        for number, line in enumerate(path.read_text().splitlines(), 1):
            code = line.split("#", 1)[0]
            if (
                "DeprecationWarning" in code
                and "simplefilter" not in code
                and "filterwarnings" not in code
            ):
                out.append(f"{name}:{number}: DeprecationWarning")
            elif "@deprecated(" in code or "renamed_keyword(" in code and "def " not in code:
                out.append(f"{name}:{number}: {code.strip()[:60]}")
    return out


def measure(root: Path) -> dict:
    mods = modules(root)
    edges = imports(root)
    top = sorted(
        m
        for m, p in mods.items()
        if m.count(".") == 1 and p.name not in ("__init__.py", "__main__.py")
    )
    long_modules = sorted(
        (
            (m, len(p.read_text().splitlines()))
            for m, p in mods.items()
            if len(p.read_text().splitlines()) > MAX_MODULE_LINES
        ),
        key=lambda item: -item[1],
    )
    cli_importers = sorted(
        {
            m
            for m, es in edges.items()
            for t, _, _ in es
            if (t == "clpde.cli" or t.startswith("clpde.cli."))
            and not (m == "clpde.cli" or m.startswith("clpde.cli.") or m == "clpde.__main__")
        }
    )
    inner = [(m, t, line) for m, es in edges.items() for t, f, line in es if f]
    typing = [f"{m} -> {t}" for m, es in imports(root, typing=True).items() for t, _, _ in es]
    return {
        "modules": len(mods),
        "top_level_modules": top,
        "cycles": cycles(edges),
        "package_cycles": cycles(package_imports(edges)),
        "ground_floor_reaching_up": ground_floor_reaching_up(root),
        "library_modules_importing_cli": cli_importers,
        "function_level_clpde_imports": len(inner),
        "function_level_clpde_import_list": [f"{m}:{line} -> {t}" for m, t, line in inner],
        "type_checking_imports": typing,
        "modules_over_600_lines": long_modules,
        "functions_over_100_code_lines": long_functions(root),
        "deprecation_shims": shims(root),
    }


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--root", type=Path, default=Path(__file__).resolve().parents[2])
    parser.add_argument("--json", type=Path, help="also write the numbers here")
    args = parser.parse_args(argv)
    result = measure(args.root)
    print(f"modules: {result['modules']}")
    print(
        f"top-level modules ({len(result['top_level_modules'])}, target <= {MAX_TOP_LEVEL}): "
        + ", ".join(m.split(".", 1)[1] for m in result["top_level_modules"])
    )
    print(f"import cycles (strongly connected components): {len(result['cycles'])}")
    for component in result["cycles"]:
        print("   ", " <-> ".join(component))
    print(f"package-level import cycles: {len(result['package_cycles'])}")
    for component in result["package_cycles"]:
        print("   ", " <-> ".join(component))
    print(
        f"ground floor reaching up: {len(result['ground_floor_reaching_up'])} "
        + ", ".join(result["ground_floor_reaching_up"])
    )
    print(
        f"library modules importing clpde.cli: {len(result['library_modules_importing_cli'])} "
        + ", ".join(result["library_modules_importing_cli"])
    )
    print(f"function-level imports of clpde modules: {result['function_level_clpde_imports']}")
    print(
        f"imports for annotations only (under TYPE_CHECKING, not counted above): "
        f"{len(result['type_checking_imports'])} " + ", ".join(result["type_checking_imports"])
    )
    print(f"modules over {MAX_MODULE_LINES} lines: {len(result['modules_over_600_lines'])}")
    for m, n in result["modules_over_600_lines"]:
        print(f"    {m}: {n}")
    print(
        f"functions over {MAX_FUNCTION_LINES} code lines: "
        f"{len(result['functions_over_100_code_lines'])}"
    )
    for m, n in result["functions_over_100_code_lines"]:
        print(f"    {m}: {n}")
    print(f"deprecation shims: {len(result['deprecation_shims'])}")
    for line in result["deprecation_shims"]:
        print(f"    {line}")
    if args.json:
        args.json.write_text(json.dumps(result, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""The public API's docstrings are numpydoc: a Parameters section that documents every
parameter, and Returns and Examples sections, for every function and class in
``clpde.__all__`` and ``clpde.surface.__all__``.

Where the docs are not there yet, the gap is listed in numpydoc_gaps.txt, and the list is
kept exact both ways: a new public name or parameter without its entry fails, and so does a
listed gap once it is documented (delete its line then). The list only shrinks.
"""

import inspect
from pathlib import Path

from numpydoc.docscrape import ClassDoc, FunctionDoc

import clpde
import clpde.surface

GAPS_FILE = Path(__file__).with_name("numpydoc_gaps.txt")


def _gaps(obj, name: str) -> list[str]:
    """What the docstring of `obj` lacks: 'name(parameter)' or 'name:Section'."""
    if inspect.isclass(obj):
        if issubclass(obj, BaseException):
            return []  # their signature is BaseException's; the docstring says when raised
        doc, target = ClassDoc(obj), obj.__init__
    elif inspect.isfunction(obj) or inspect.ismethod(obj):
        doc, target = FunctionDoc(obj), obj
    else:
        return []  # constants and modules
    documented = {
        part.strip().lstrip("*") for entry in doc["Parameters"] for part in entry.name.split(",")
    }
    out = [
        f"{name}({p.name})"
        for p in inspect.signature(target).parameters.values()
        if p.name not in ("self", "cls") and not p.name.startswith("_") and p.name not in documented
    ]
    if not inspect.isclass(obj):
        out += [f"{name}:{section}" for section in ("Returns", "Examples") if not doc[section]]
    return out


def public_gaps() -> list[str]:
    out = []
    for module in (clpde, clpde.surface):
        for name in module.__all__:
            out += _gaps(getattr(module, name), f"{module.__name__}.{name}")
    return out


def test_the_check_sees_a_missing_parameter():
    def documented(a: int, b: int) -> int:
        """Add.

        Parameters
        ----------
        a : int
            One.

        Returns
        -------
        int

        Examples
        --------
        >>> documented(1, 2)
        3
        """
        return a + b

    assert _gaps(documented, "f") == ["f(b)"]


def test_public_docstrings_are_numpydoc_except_the_listed_gaps():
    listed = [line for line in GAPS_FILE.read_text().splitlines() if line.strip()]
    found = public_gaps()
    new = sorted(set(found) - set(listed))
    closed = sorted(set(listed) - set(found))
    assert not new, "public names or parameters without numpydoc docs:\n" + "\n".join(new)
    assert not closed, "documented now: delete these lines from numpydoc_gaps.txt:\n" + "\n".join(
        closed
    )


def test_public_signatures_have_type_hints():
    missing = []
    for module in (clpde, clpde.surface):
        for name in module.__all__:
            obj = getattr(module, name)
            if inspect.isclass(obj):
                if issubclass(obj, BaseException):
                    continue
                target = obj.__init__
            elif inspect.isfunction(obj):
                target = obj
            else:
                continue
            signature = inspect.signature(target)
            missing += [
                f"{module.__name__}.{name}({p.name})"
                for p in signature.parameters.values()
                if p.name not in ("self", "cls")
                and not p.name.startswith("_")
                and p.annotation is inspect.Parameter.empty
            ]
            if not inspect.isclass(obj) and signature.return_annotation is inspect.Signature.empty:
                missing.append(f"{module.__name__}.{name} (return)")
    assert not missing, "public signatures without type hints:\n" + "\n".join(missing)


def test_every_public_parameter_has_its_own_typed_entry_and_none_is_private():
    """numpydoc's own validation: every parameter documented (PR01), nothing documented
    that is not one (PR02), each with a type (PR04); and no private (_name) parameter in a
    public signature, where a user would see it."""
    from numpydoc.validate import validate

    problems = []
    for module in (clpde, clpde.surface):
        for name in module.__all__:
            obj = getattr(module, name)
            if inspect.isclass(obj) and issubclass(obj, BaseException):
                continue
            if not (inspect.isclass(obj) or inspect.isfunction(obj)):
                continue
            full = f"{module.__name__}.{name}"
            problems += [
                f"{full}: {code} {message}"
                for code, message in validate(full)["errors"]
                if code in ("PR01", "PR02", "PR04")
            ]
            target = obj.__init__ if inspect.isclass(obj) else obj
            problems += [
                f"{full}: private parameter {p}"
                for p in inspect.signature(target).parameters
                if p.startswith("_")
            ]
    assert not problems, "\n".join(problems)


def test_the_flows_are_documented_methods_of_the_surface_only():
    """The flows on a surface have one public form, ImplicitSurface's methods (issue 38):
    those carry the complete numpydoc docs and type hints that public functions carry, and
    clpde.surface has no function of the same name."""
    from numpydoc.validate import validate

    from clpde.surface.flow_methods import FlowMethods
    from clpde.surface.shape_methods import ShapeMethods

    names = [n for base in (FlowMethods, ShapeMethods) for n in vars(base) if n[0] != "_"]
    assert {"heat", "tv", "denoise_tv", "denoise_colour", "render"} <= set(names)
    problems = []
    for name in names:
        method = getattr(clpde.surface.ImplicitSurface, name)
        full = f"clpde.surface.ImplicitSurface.{name}"
        problems += _gaps(method, full)
        problems += [
            f"{full}: {code} {message}"
            for code, message in validate(full)["errors"]
            if code in ("PR01", "PR02", "PR04")
        ]
        signature = inspect.signature(method)
        problems += [
            f"{full}({p.name}) has no type hint"
            for p in signature.parameters.values()
            if p.name != "self" and p.annotation is inspect.Parameter.empty
        ]
        if signature.return_annotation is inspect.Signature.empty:
            problems.append(f"{full} (return) has no type hint")
        if name in clpde.surface.__all__ or inspect.isfunction(getattr(clpde.surface, name, None)):
            problems.append(f"clpde.surface.{name} is a second public form of {full}")
    assert not problems, "\n".join(problems)

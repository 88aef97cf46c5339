"""Every Python block of the README and of the current docs pages runs, in order, as a
reader would paste them, with clpde's own DeprecationWarnings as errors.

History pages (the thesis's first versions, kept for their measurements) are excluded by
name. A block that needs data or hardware that is not bundled is skipped when the line
before its fence is `<!-- skip: REASON -->`, with the reason given."""

import re
import warnings
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
# Pages that record earlier versions; their code shows the API of that time.
HISTORY = "docs/history"  # pages of earlier versions: their code is of its time
BLOCK = re.compile(
    r"(?:^<!--\s*skip:(?P<reason>[^>]*)-->\s*\n)?^```python\n(?P<code>.*?)^```", re.S | re.M
)


def pages():
    found = [ROOT / "README.md", *sorted((ROOT / "docs").rglob("*.md"))]
    return [p for p in found if not p.relative_to(ROOT).as_posix().startswith(HISTORY + "/")]


def blocks(page: Path):
    """(line, code, skip reason or None) of each Python block, in order."""
    text = page.read_text()
    out = []
    for m in BLOCK.finditer(text):
        reason = m.group("reason")
        if reason is not None:
            assert reason.strip(), f"{page.name}: a skip marker without its reason"
        line = text.count("\n", 0, m.start("code")) + 1
        out.append((line, m.group("code"), None if reason is None else reason.strip()))
    return out


def test_the_history_pages_exist_and_say_so():
    history = sorted((ROOT / HISTORY).glob("*.md"))
    assert history
    for page in history:  # the exclusion must not hide a current page
        assert "version" in page.read_text()[:600].lower(), page.name


@pytest.mark.parametrize("page", pages(), ids=lambda p: p.relative_to(ROOT).as_posix())
def test_python_blocks_run_in_order(page, tmp_path, monkeypatch):
    found = blocks(page)
    if not found:
        pytest.skip("no Python blocks")
    monkeypatch.chdir(tmp_path)  # blocks that save files write here
    run_blocks(page, found)
    if all(reason for _, _, reason in found):
        pytest.skip("; ".join(reason for _, _, reason in found))


def run_blocks(page: Path, found) -> None:
    # the examples run as a module named like clpde's, so that the filter on module "clpde"
    # catches clpde's deprecations both where clpde raises them and where they are
    # attributed to the example's call (stacklevel)
    namespace = {"__name__": "clpde_docs_example"}
    with warnings.catch_warnings():
        warnings.filterwarnings("error", category=DeprecationWarning, module="clpde")
        for line, code, reason in found:
            if reason is None:
                compiled = compile(code, f"{page.name}:{line}", "exec")
                exec(compiled, namespace)  # noqa: S102  (the documentation's own examples)


def test_a_deprecated_call_in_a_block_fails(tmp_path):
    page = tmp_path / "page.md"
    page.write_text(
        "<!-- skip: not run -->\n```python\nraise SystemExit\n```\n\n```python\n"
        "import warnings\n\nwarnings.warn_explicit('use iterate()', "
        "DeprecationWarning, 'clpde/x.py', 1, module='clpde.tracking')\n```\n"
    )
    found = blocks(page)
    assert [reason for _, _, reason in found] == ["not run", None]
    with pytest.raises(DeprecationWarning, match="iterate"):
        run_blocks(page, found)

"""Docs that run as written: every ```python block of README.md and docs/*.md is executed,
the blocks of one page in order in one namespace (as a reader pastes them into one session),
in a scratch directory. A deliberate fragment (an API synopsis, a script for a cluster) has
``<!-- not run -->`` on the line before its fence; ``<!-- requires: chromium -->`` skips a
block, saying so, where the headless browser the animations need is missing."""

from __future__ import annotations

import ast
import builtins
import re
import shutil
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
ALL_PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
FENCE = re.compile(r"^```python\s*$")
MARK = re.compile(r"^<!--\s*(not run|requires:\s*([\w, -]+?))\s*-->\s*$")


def blocks(page: Path) -> list[tuple[int, str | None, str]]:
    """(line of the fence, the marker before it or None, code) for each python block."""
    lines = page.read_text(encoding="utf-8").splitlines()
    out, i = [], 0
    while i < len(lines):
        if FENCE.match(lines[i]):
            start, marker = i + 1, None
            m = MARK.match(lines[i - 1].strip()) if i > 0 else None
            if m:
                marker = m.group(1)
            j = i + 1
            while j < len(lines) and not lines[j].startswith("```"):
                j += 1
            out.append((start, marker, "\n".join(lines[i + 1 : j]) + "\n"))
            i = j
        i += 1
    return out


def _chromium() -> bool:
    return any(shutil.which(b) for b in ("chromium", "chromium-browser", "google-chrome"))


REQUIREMENTS = {"chromium": _chromium}
PAGES = [p for p in ALL_PAGES if blocks(p)]


def test_every_page_is_collected():
    # The pages this test reads exist and hold blocks (a moved docs folder must not make
    # this suite pass vacuously).
    assert (ROOT / "README.md").is_file()
    assert sum(len(blocks(p)) for p in ALL_PAGES) >= 10


@pytest.mark.parametrize("page", PAGES, ids=[p.relative_to(ROOT).as_posix() for p in PAGES])
def test_python_blocks_run(page, tmp_path, monkeypatch, request):
    if page == ROOT / "docs" / "design.md":
        # Run once per session, shared with tests/test_design_connected.py (conftest.py).
        request.getfixturevalue("design_page_run")
        return
    found = blocks(page)
    monkeypatch.chdir(tmp_path)
    pytest.importorskip("matplotlib").use("Agg")  # blocks that plot write files only
    namespace: dict = {"__name__": f"docs.{page.stem}"}
    skipped = []
    for line, marker, code in found:
        where = f"{page.relative_to(ROOT)}:{line}"
        if marker == "not run":  # may be a synopsis, not Python at all
            continue
        if marker and marker.startswith("requires:"):
            missing = [r.strip() for r in marker.split(":", 1)[1].split(",")
                       if not REQUIREMENTS[r.strip()]()]
            if missing:
                skipped.append(f"{where} needs {', '.join(missing)}")
                continue
        try:
            exec(compile(code, where, "exec"), namespace)
        except Exception as e:
            raise AssertionError(f"the python block at {where} fails: {e!r}") from e
    if skipped:
        pytest.skip("; ".join(skipped))


def _names(tree) -> tuple[set, set]:
    """(names a block defines, names it reads) at any depth."""
    defined, used = set(), set()
    for n in ast.walk(tree):
        if isinstance(n, ast.Name):
            (used if isinstance(n.ctx, ast.Load) else defined).add(n.id)
        elif isinstance(n, (ast.Import, ast.ImportFrom)):
            defined |= {(a.asname or a.name).split(".")[0] for a in n.names}
        elif isinstance(n, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
            defined.add(n.name)
        elif isinstance(n, ast.arg):
            defined.add(n.arg)
        elif isinstance(n, ast.ExceptHandler) and n.name:
            defined.add(n.name)
    return defined, used


def test_visualisation_runs_every_block_but_the_live_view():
    # Issue 38 #9: the Panda block (the one that made docs/panda.gif) failed with
    # NameError: robots, unnoticed because it was not run. Now only the Meshcat live view is
    # left out (it starts a server and opens a browser tab), and it reads only names the
    # page's blocks before it define, as a reader pasting them in order would.
    page = ROOT / "docs" / "visualisation.md"
    known = set(dir(builtins))
    for line, marker, code in blocks(page):
        defined, used = _names(ast.parse(code))
        if marker == "not run":
            assert "show_meshcat" in code, f"visualisation.md:{line} is not run"
            assert used <= known | defined, (line, sorted(used - known - defined))
        known |= defined


RUST_PATH = re.compile(r"\brust/[\w/]*\w(?:\.rs|/)")


def test_rust_paths_in_the_pages_exist():
    """Every `rust/...` file or folder a page names is in the tree (the guides' `foo.rs`, the
    file a reader adds, excepted): docs/architecture.md describes the real tree."""
    missing = {f"{page.relative_to(ROOT)}: {path}" for page in ALL_PAGES
               for path in RUST_PATH.findall(page.read_text())
               if not (ROOT / path).exists() and not path.endswith("/foo.rs")}
    assert missing == set()


def test_architecture_names_every_folder_of_the_core():
    text = (ROOT / "docs" / "architecture.md").read_text()
    folders = {p.name for p in (ROOT / "rust").iterdir() if p.is_dir()}
    assert len(folders) > 10
    assert {f for f in folders if f"{f}/" not in text} == set()

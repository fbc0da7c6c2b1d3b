"""The sizes we keep (docs/architecture.md): library Rust files under 900 lines and Rust
functions under 120, Python modules under 600 lines and Python functions under 120 (their
docstrings and the functions defined inside them not counted), the bindings (``rust/python/``) under 4,000 lines. A function past
its limit carries its reason beside it: a ``long:`` comment on the lines just above a Rust
``fn`` or on a Python ``def`` line."""

from __future__ import annotations

import ast
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
RUST = ROOT / "rust"
PYTHON = ROOT / "python" / "pointmass_dyn"
RUST_FILE, RUST_FN, PY_MODULE, PY_FN, BINDINGS = 900, 120, 600, 120, 4000


def library_lines(path: Path) -> list[str]:
    """A Rust file's lines before its `#[cfg(test)]` block (its tests are not library)."""
    out = []
    for line in path.read_text().splitlines():
        if line.strip().startswith("#[cfg(test)]"):
            break
        out.append(line)
    return out


def library_files() -> list[Path]:
    return [p for p in sorted(RUST.rglob("*.rs"))
            if "tests" not in p.relative_to(RUST).parts[:-1] and not p.name.endswith("tests.rs")]


FN = re.compile(r"^\s*(pub(\([^)]*\))?\s+)?(const\s+)?(unsafe\s+)?fn\s+(\w+)")
# Strings, character literals and comments, which may hold braces that are not code.
NOT_CODE = re.compile(r'"(\\.|[^"\\])*"|\'(\\.|[^\'\\])\'|//.*$')


def rust_functions(lines: list[str]):
    """``(name, first line, length)`` of each function: from its ``fn`` to its closing brace."""
    for i, line in enumerate(lines):
        m = FN.match(line)
        if not m:
            continue
        depth, opened = 0, False
        for j in range(i, len(lines)):
            code = NOT_CODE.sub("", lines[j])
            if not opened and ";" in code and "{" not in code:
                break  # a declaration without a body (a trait's required method)
            depth += code.count("{") - code.count("}")
            opened = opened or "{" in code
            if opened and depth <= 0:
                yield m.group(5), i, j - i + 1
                break


def own_lines(node: ast.FunctionDef | ast.AsyncFunctionDef) -> int:
    """A Python function's lines less its docstring and the functions defined inside it
    (each of those is measured on its own)."""
    n = node.end_lineno - node.lineno + 1
    doc = node.body[0]
    if isinstance(doc, ast.Expr) and isinstance(doc.value, ast.Constant) \
            and isinstance(doc.value.value, str):
        n -= doc.end_lineno - doc.lineno + 1
    for inner in ast.walk(node):
        if inner is not node and isinstance(inner, (ast.FunctionDef, ast.AsyncFunctionDef)) \
                and not any(inner in ast.walk(mid) for mid in ast.walk(node)
                            if mid is not node and mid is not inner
                            and isinstance(mid, (ast.FunctionDef, ast.AsyncFunctionDef))):
            n -= inner.end_lineno - inner.lineno + 1
    return n


def test_the_size_checks_see_what_they_measure():
    """The brace counter on a known function, so that the limits below cannot pass vacuously."""
    lines = ['pub fn f(x: &str) -> usize {', '    let s = "}{";', "    if x == s {", "        1",
             "    } else { 2 } // }", "}", "fn g();"]
    assert list(rust_functions(lines)) == [("f", 0, 6)]
    code = 'def f():\n    """Doc."""\n    def g():\n        return 1\n    return g\n'
    assert own_lines(ast.parse(code).body[0]) == 2
    assert len(library_files()) > 100 and len(list(PYTHON.rglob("*.py"))) > 40


def test_library_rust_files_stay_under_the_limit():
    big = {str(p.relative_to(ROOT)): n for p in library_files()
           if (n := len(library_lines(p))) > RUST_FILE}
    assert big == {}


def test_rust_functions_stay_under_the_limit_or_say_why():
    long = {}
    for p in library_files():
        lines = library_lines(p)
        for name, i, n in rust_functions(lines):
            reason = any("long:" in lines[k] for k in range(max(0, i - 3), i))
            if n > RUST_FN and not reason:
                long[f"{p.relative_to(ROOT)}::{name}"] = n
    assert long == {}


def test_python_modules_and_functions_stay_under_the_limits():
    big, long = {}, {}
    for p in sorted(PYTHON.rglob("*.py")):
        text = p.read_text()
        lines = text.splitlines()
        if len(lines) > PY_MODULE:
            big[str(p.relative_to(ROOT))] = len(lines)
        for node in ast.walk(ast.parse(text)):
            if not isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                continue
            n = own_lines(node)
            if n > PY_FN and "long:" not in lines[node.lineno - 1]:
                long[f"{p.relative_to(ROOT)}::{node.name}"] = n
    assert (big, long) == ({}, {})


@pytest.mark.xfail(strict=True, reason="issue 40: the typed run configuration and result are "
                   "shrinking the bindings towards 4,000 lines; remove this mark when they pass")
def test_the_bindings_stay_under_the_limit():
    files = sorted((RUST / "python").rglob("*.rs"))
    n = sum(len(library_lines(p)) for p in files)
    assert n <= BINDINGS, f"rust/python/ holds {n} lines"

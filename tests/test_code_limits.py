"""The sizes we keep (docs/architecture.md): library Rust files under 900 lines and Rust
functions under 120, Python modules under 600 lines and Python functions under 120 (their
docstrings and the functions defined inside them not counted), the bindings (``rust/python/``) under 4,000 lines. A function past
its limit carries its reason beside it: a ``long:`` comment on the lines just above a Rust
``fn`` or on a Python ``def`` line. And the layers of the Rust tree: at most two import
cycles between its concepts, the linear algebra a leaf (``python tests/test_code_limits.py``
prints the graph)."""

from __future__ import annotations

import ast
import re
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
RUST = ROOT / "rust"
PYTHON = ROOT / "python" / "pointmass_dyn"
RUST_FILE, RUST_FN, PY_MODULE, PY_FN, BINDINGS = 900, 120, 600, 120, 4000


def library_lines(path: Path) -> list[str]:
    """A Rust file's lines less its ``#[cfg(test)]`` items (a ``mod tests;`` declaration or a
    ``mod tests { ... }`` block, wherever it stands): everything else is library."""
    lines, out, i = path.read_text().splitlines(), [], 0
    while i < len(lines):
        if not lines[i].strip().startswith("#[cfg(test)]"):
            out.append(lines[i])
            i += 1
            continue
        i += 1  # the item after the attribute: to its `;`, or to its block's closing brace
        depth, opened = 0, False
        while i < len(lines):
            code = NOT_CODE.sub("", lines[i])
            depth += code.count("{") - code.count("}")
            opened = opened or "{" in code
            i += 1
            if (opened and depth <= 0) or (not opened and code.rstrip().endswith(";")):
                break
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
    # Only the `#[cfg(test)]` items leave the count: a `mod tests;` declared at the top does
    # not hide the library below it, and a test block in the middle hides only itself.
    rs = ROOT / "target" / "code_limits_probe.rs"
    rs.parent.mkdir(exist_ok=True)
    rs.write_text("#[cfg(test)]\nmod tests;\nfn a() {}\n#[cfg(test)]\nmod t {\n    fn b() {}\n}\nfn c() {}\n")
    assert library_lines(rs) == ["fn a() {}", "fn c() {}"]
    rs.unlink()
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


def test_the_bindings_stay_under_the_limit():
    """The bindings only convert and declare (issue 40): what grows past this belongs in the
    core, read through `support::args::Arg`."""
    files = sorted((RUST / "python").rglob("*.rs"))
    n = sum(len(library_lines(p)) for p in files)
    assert n <= BINDINGS, f"rust/python/ holds {n} lines"


# --- The layers of the Rust tree (docs/architecture.md) ------------------------------------
# The graph: file A -> file B when A names B's module in a path (`use crate::…`, `super::…`,
# or written out in the code), library code only (`#[cfg(test)]` items, tests/ folders and
# the benchmark fixtures left out). A *concept* is a top-level folder of rust/, except in the
# folders that group several concepts of one layer, where it is their child.
GROUPS = ("support", "io", "dynamics")
CFG_TEST = "#[cfg(test)]"


def rust_module(path: Path) -> tuple[str, ...]:
    parts = list(path.relative_to(RUST).with_suffix("").parts)
    return tuple(parts[:-1] if parts[-1] in ("mod", "lib") else parts)


def concept(module: tuple[str, ...]) -> str:
    if not module:
        return "lib"
    return "/".join(module[:2]) if module[0] in GROUPS and len(module) > 1 else module[0]


def without_tests(text: str) -> str:
    """The text less its comments and each `#[cfg(test)]` item (to its `;` or closing brace)."""
    text = re.sub(r"//[^\n]*", "", text)
    out, i = [], 0
    while (j := text.find(CFG_TEST, i)) >= 0:
        out.append(text[i:j])
        k, depth = j + len(CFG_TEST), 0
        while k < len(text):
            c, k = text[k], k + 1
            depth += (c == "{") - (c == "}")
            if (c == "}" and depth == 0) or (c == ";" and depth == 0):
                break
        i = k
    return "".join(out) + text[i:]


def use_paths(tree: str) -> list[str]:
    """`a::{b, c::{d as e}}` -> `a::b`, `a::c::d`."""
    tree = re.sub(r"\s+", "", tree)
    if "{" not in tree:
        return [re.sub(r"as\w+$", "", tree)] if tree else []
    i = tree.index("{")
    items, depth, cur = [], 0, ""
    for c in tree[i + 1:-1]:
        if c == "," and depth == 0:
            items.append(cur)
            cur = ""
            continue
        depth += (c == "{") - (c == "}")
        cur += c
    items.append(cur)
    return [tree[:i] + x for item in items for x in use_paths(item)]


def use_graph() -> dict[tuple[str, ...], set[tuple[str, ...]]]:
    """File-level graph, each file named by its module path."""
    files = [p for p in library_files() if p.name != "benchmark_models.rs"]
    modules = {rust_module(p) for p in files}
    graph = {}
    for p in files:
        me = rust_module(p)
        text = without_tests(p.read_text())
        paths = [x for m in re.finditer(r"\buse\s+([^;]+);", text) for x in use_paths(m.group(1))]
        rest = re.sub(r"\buse\s+[^;]+;", "", text)
        paths += re.findall(r"\b(?:crate|super|self)(?:::\w+)+", rest)
        targets = set()
        for path in paths:
            segs = [s for s in path.split("::") if s]
            if segs[0] == "crate":
                base, segs = (), segs[1:]
            elif segs[0] in ("super", "self"):
                base = me
                while segs and segs[0] in ("super", "self"):
                    base = base[:-1] if segs.pop(0) == "super" else base
            elif me + (segs[0],) in modules:  # a child module, named from its parent
                base = me
            else:
                continue  # another crate's path
            full = base + tuple(segs)
            target = next(full[:n] for n in range(len(full), -1, -1) if full[:n] in modules or n == 0)
            if target != me and target in modules:
                targets.add(target)
        graph[me] = targets
    return graph


def concept_graph(graph) -> dict[str, set[str]]:
    out: dict[str, set[str]] = {}
    for a, targets in graph.items():
        for b in targets:
            if concept(a) != concept(b) and concept(b) != "lib":
                out.setdefault(concept(a), set()).add(concept(b))
    return out


def cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """Every elementary cycle, each once (started at its least node)."""
    found = []

    def walk(start, node, path):
        for nxt in sorted(graph.get(node, ())):
            if nxt == start:
                found.append(list(path))
            elif nxt > start and nxt not in path:
                walk(start, nxt, path + [nxt])

    for start in sorted(set(graph) | {b for bs in graph.values() for b in bs}):
        walk(start, start, [start])
    return found


def test_the_import_graph_sees_what_it_measures():
    """Known edges and a known cycle, so that the count below cannot pass vacuously."""
    graph = use_graph()
    assert ("model", "body") in graph[("model",)]  # `use crate::model::body::RigidBody`
    assert ("model",) in graph[("recursive", "aba")]
    assert ("support", "cpu") in graph[("linalg", "spd")]
    assert ("io", "urdf", "parse") in graph[("io", "urdf", "build")]  # `use super::parse::…`
    assert concept(("io", "urdf", "parse")) == "io/urdf" and concept(("model", "body")) == "model"
    assert use_paths("crate::a::{b, c::{d as e, f}}") == ["crate::a::b", "crate::a::c::d",
                                                          "crate::a::c::f"]
    assert without_tests("use a;\n#[cfg(test)]\nmod tests {\n use b; {}\n}\nuse c;") \
        == "use a;\n\nuse c;"
    toy = {"a": {"b"}, "b": {"a", "c"}, "c": {"a"}}
    assert cycles(toy) == [["a", "b"], ["a", "b", "c"]]


def test_at_most_two_import_cycles_between_concepts():
    """Today's two: the model keeps the recursions' constants (`recursive::Compiled`, which
    reads the model), and the recursions read the world kinematics (which read the model)."""
    found = [" -> ".join(c + [c[0]]) for c in cycles(concept_graph(use_graph()))]
    assert len(found) <= 2, found


def test_linear_algebra_is_a_leaf():
    """`linalg/` uses nothing of the crate but `support/` (and itself)."""
    outside = {"/".join(b) for a, bs in use_graph().items() if a[:1] == ("linalg",)
               for b in bs if b[:1] not in (("linalg",), ("support",))}
    assert outside == set()


def test_benchmark_fixtures_are_not_in_the_shipped_library():
    lib = (RUST / "lib.rs").read_text()
    gate = '#[cfg(any(test, feature = "benchmark-models"))]\npub mod benchmark_models;'
    assert gate in lib and lib.count("benchmark_models") == 1


if __name__ == "__main__":
    concepts = concept_graph(use_graph())
    for name in sorted(concepts):
        print(f"{name} -> {' '.join(sorted(concepts[name]))}")
    print("cycles:", *[" -> ".join(c + [c[0]]) for c in cycles(concepts)], sep="\n  ")
    sys.exit(0)

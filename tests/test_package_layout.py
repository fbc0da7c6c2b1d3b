"""The Python package's structure (docs/architecture.md, "The Python package"): no import
cycles, no private names imported across modules, a private module used only inside its own
package, our own modules imported at module level (a cycle cannot hide in a function), no
module over 600 lines; every module imports first in a fresh interpreter; the benchmarking
tools load on first use."""

from __future__ import annotations

import ast
import importlib.util
import subprocess
import sys
from pathlib import Path

import pointmass_dyn as pmd
import pytest

PACKAGE = Path(pmd.__file__).parent
ROOT = "pointmass_dyn"
MAX_LINES = 600


def _modules() -> dict[str, Path]:
    """Every Python module of the package by dotted name (a package by its ``__init__``)."""
    out = {}
    for path in sorted(PACKAGE.rglob("*.py")):
        parts = path.relative_to(PACKAGE).with_suffix("").parts
        if parts[-1] == "__init__":
            parts = parts[:-1]
        out[".".join((ROOT, *parts))] = path
    return out


MODULES = _modules()
#: Modules that exist but are not Python source (the compiled extension).
EXTENSION = {f"{ROOT}._core"}


def _is_package(name: str) -> bool:
    return MODULES[name].name == "__init__.py"


def _imports(name: str):
    """``(target module, imported name or None, line, at module level)`` of every import in
    module ``name`` that resolves inside the package."""
    tree = ast.parse(MODULES[name].read_text(encoding="utf-8"))
    package = name if _is_package(name) else name.rpartition(".")[0]
    top_level = {id(n) for n in tree.body}
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for alias in node.names:
                if alias.name == ROOT or alias.name.startswith(ROOT + "."):
                    yield alias.name, None, node.lineno, id(node) in top_level
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")
                base = base[: len(base) - (node.level - 1)]
                target = ".".join(base + ([node.module] if node.module else []))
            else:
                target = node.module or ""
            if target != ROOT and not target.startswith(ROOT + "."):
                continue
            for alias in node.names:
                sub = f"{target}.{alias.name}"
                if sub in MODULES or sub in EXTENSION:
                    yield sub, None, node.lineno, id(node) in top_level
                else:
                    yield target, alias.name, node.lineno, id(node) in top_level


def _private(part: str) -> bool:
    return part.startswith("_") and not (part.startswith("__") and part.endswith("__"))


def test_no_module_over_600_lines():
    long = {n: len(p.read_text(encoding="utf-8").splitlines()) for n, p in MODULES.items()}
    assert {n: k for n, k in long.items() if k > MAX_LINES} == {}


def test_own_modules_are_imported_at_module_level():
    """A function-level import of our own module is how the old cycles hid."""
    late = [f"{n}:{line} imports {t}" for n in MODULES for t, _, line, top in _imports(n)
            if not top]
    assert late == []


def test_no_private_name_is_imported_across_modules():
    """``from .x import _name`` nowhere; and a private module (``_x``) or a name inside one is
    imported only from within the package that holds it (``viewer._drawing`` by the
    ``viewer`` package's modules, ``pointmass_dyn._helpers`` by any of ours)."""
    bad = []
    for n in MODULES:
        for target, attr, line, _ in _imports(n):
            if attr is not None and _private(attr):
                bad.append(f"{n}:{line} imports the private name {target}.{attr}")
            parts = target.split(".")
            for k, part in enumerate(parts):
                owner = ".".join(parts[:k])
                if _private(part) and not (n == owner or n.startswith(owner + ".")):
                    bad.append(f"{n}:{line} reaches into {target}, private to {owner}")
    assert bad == []


def _graph() -> dict[str, set[str]]:
    edges: dict[str, set[str]] = {n: set() for n in MODULES}
    for n in MODULES:
        for target, _, _, _ in _imports(n):
            if target in MODULES:
                edges[n].add(target)
    return edges


def _cycles(edges: dict[str, set[str]]) -> list[list[str]]:
    """The import cycles of a graph (one path per strongly connected component of more than
    one module, or a module that imports itself)."""
    index, low, stack, on, out = {}, {}, [], set(), []

    def visit(v):
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        for w in sorted(edges[v]):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1 or v in edges[v]:
                out.append(sorted(comp))

    for v in sorted(edges):
        if v not in index:
            visit(v)
    return out


def test_cycle_finder_finds_a_cycle():
    """The check below can fail: a cycle through three modules and a self-import are found."""
    assert _cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]
    assert _cycles({"a": {"a"}}) == [["a"]]
    assert _cycles({"a": {"b"}, "b": set()}) == []


def test_import_graph_has_no_cycles():
    """Static: every import of one of our modules by another (module level or not; a parent
    package's implicit import aside), as an edge; no cycle."""
    edges = _graph()
    assert sum(map(len, edges.values())) > 50  # the graph was read
    assert _cycles(edges) == []


#: Top-level modules that import the parts: the public API and ``python -m pointmass_dyn``.
TOP_IMPORTERS = {ROOT, f"{ROOT}.__main__"}


def test_parts_depend_downwards():
    """cli → benchmarking, identification, design, viewer, io → the core: a part imports only the parts
    below it, the core none (docs/architecture.md)."""
    below = {
        "cli": {"benchmarking", "design", "identification", "viewer", "io"},
        "benchmarking": {"io"},
        "identification": {"design"},
        "viewer": {"design"},
        "design": set(),
        "io": set(),
    }

    def part(name):
        p = name.split(".")
        return p[1] if len(p) > 1 and p[1] in below else "core"

    wrong = set()
    for n, targets in _graph().items():
        for t in targets:
            a, b = part(n), part(t)
            if b != a and b != "core" and a != "core" and b not in below[a]:
                wrong.add((n, t))
            # The core imports no part: only the package's __init__ (the public API) and
            # __main__ (the CLI) do.
            if a == "core" and b != "core" and n not in TOP_IMPORTERS:
                wrong.add((n, t))
    assert wrong == set()


#: Module paths of the flat layout before the subpackages: never shipped, so not kept.
FORMER = ("animation", "balancing", "importers", "mjcf", "viewer_video", "work_precision",
          "work_precision_methods")


@pytest.mark.parametrize("name", sorted(n for n in MODULES if not n.endswith(".__main__")))
def test_every_module_imports_first_in_a_fresh_interpreter(name):
    """Dynamic: whichever module a program imports first, the import succeeds (a cycle that
    only bites in one order would fail here)."""
    run = subprocess.run([sys.executable, "-c", f"import {name}"], capture_output=True,
                         text=True, timeout=120)
    assert run.returncode == 0, run.stderr[-2000:]


def test_importing_the_package_does_not_load_the_benchmarking_tools():
    """``import pointmass_dyn`` loads what simulating needs; ``pmd.work_precision`` and
    ``pmd.benchmarking`` load the benchmarking subpackage on first use."""
    code = ("import sys, pointmass_dyn as pmd\n"
            "assert 'pointmass_dyn.benchmarking' not in sys.modules\n"
            "assert pmd.work_precision is pmd.benchmarking.work_precision\n"
            "assert pmd.WorkPrecision is pmd.benchmarking.WorkPrecision\n"
            "assert 'pointmass_dyn.benchmarking' in sys.modules\n")
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         timeout=120)
    assert run.returncode == 0, run.stderr[-2000:]


@pytest.mark.parametrize("name", FORMER)
def test_the_flat_layouts_module_paths_are_gone(name):
    """No aliases for module paths that never shipped."""
    assert importlib.util.find_spec(f"{ROOT}.{name}") is None
    with pytest.raises(AttributeError):
        getattr(pmd, name if name != "work_precision" else "no_such_module")


def test_every_public_name_of_the_package_resolves():
    import pointmass_dyn.cli  # noqa: F401  (not imported by the package itself)

    missing = [n for n in pmd.__all__ if not hasattr(pmd, n)]
    assert missing == []
    for sub in (pmd.io, pmd.viewer, pmd.design, pmd.benchmarking, pmd.cli):
        assert [n for n in sub.__all__ if not hasattr(sub, n)] == [], sub.__name__


def test_bundled_data_sits_beside_the_code_that_reads_it():
    """viewer.js (read by the page writer) and the bundled scenes ship inside the package."""
    assert (PACKAGE / "viewer" / "viewer.js").is_file()
    assert len(pmd.builtin_scenes()) >= 10
    assert all(p.parent == PACKAGE / "scenes" for p in pmd.builtin_scenes().values())

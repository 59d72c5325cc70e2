"""The package layout (docs/conventions.md, "Package layout"): subpackages by concept, no
import cycles, no module over 600 lines, no caches in module globals.

The import graph is read from the source (every ``import``/``from`` statement, also those
inside functions, which are cycles deferred to run time; those under ``if TYPE_CHECKING:``
are annotations only and do not count).
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[1] / "nlgrd"
MAX_LINES = 600
#: Modules reviewed as one concept above MAX_LINES: (ceiling, why it is one concept).
LONG_MODULES = {
    "nlgrd.nonlinear.floquet": (
        760,
        "the monodromy of an HB orbit: its exact piecewise product, the Magnus product for "
        "smooth tangents on the same pieces, and the verdict; the two products share the pieces",
    ),
    "nlgrd.plotting.common": (
        660,
        "the conventions every figure shares: axis labels from column names, legends placed "
        "outside, stability line styles, the no-measurement note",
    ),
}

#: What each subpackage may import from nlgrd (besides itself and the top-level helpers
#: nlgrd.errors, nlgrd.cache and nlgrd.threads): the
#: layers, lowest first. Plotting draws results and imports no analysis module.
ALLOWED = {
    "rotor": {"plotting"},
    "gear": {"plotting"},
    "plotting": set(),
    "nonlinear": {"rotor", "gear", "plotting"},
    "timedomain": {"rotor", "gear", "nonlinear", "plotting"},  # plotting: RampResult.plot
    "io": {"rotor", "gear", "nonlinear"},
    "studies": {"rotor", "gear", "nonlinear", "timedomain", "io", "plotting", "cli", "nlgrd"},
}


def _module_name(path: Path) -> str:
    parts = path.relative_to(PACKAGE.parent).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _modules() -> dict[str, Path]:
    return {_module_name(p): p for p in sorted(PACKAGE.rglob("*.py"))}


def _is_type_checking(node: ast.If) -> bool:
    t = node.test
    return (isinstance(t, ast.Name) and t.id == "TYPE_CHECKING") or (
        isinstance(t, ast.Attribute) and t.attr == "TYPE_CHECKING"
    )


def _imports(tree: ast.AST, modules: dict[str, Path], own: str) -> set[str]:
    """nlgrd modules imported anywhere in ``tree`` outside ``if TYPE_CHECKING:`` blocks."""
    out: set[str] = set()

    def visit(node):
        if isinstance(node, ast.If) and _is_type_checking(node):
            for child in node.orelse:
                visit(child)
            return
        if isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            if node.module.startswith("nlgrd"):
                for alias in node.names:
                    full = f"{node.module}.{alias.name}"
                    out.add(full if full in modules else node.module)
        elif isinstance(node, ast.Import):
            out.update(a.name for a in node.names if a.name.startswith("nlgrd"))
        for child in ast.iter_child_nodes(node):
            visit(child)

    visit(tree)
    out.discard(own)
    return {m for m in out if m in modules}


def import_graph() -> dict[str, set[str]]:
    mods = _modules()
    return {m: _imports(ast.parse(p.read_text(encoding="utf-8")), mods, m) for m, p in mods.items()}


def _cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected components with more than one module (Tarjan)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on: set[str] = set()
    out: list[list[str]] = []

    def strong(v):
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        for w in sorted(graph[v]):
            if w not in index:
                strong(w)
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
            if len(comp) > 1:
                out.append(sorted(comp))

    for v in sorted(graph):
        if v not in index:
            strong(v)
    return out


def test_the_cycle_finder_finds_a_cycle():
    """The check below can fail: a deferred two-module cycle is found."""
    graph = {"a": {"b"}, "b": {"a"}, "c": {"a"}}
    assert _cycles(graph) == [["a", "b"]]
    tree = ast.parse(
        "from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n    import nlgrd.x\n"
        "def f():\n    import nlgrd.y\n"
    )
    assert _imports(tree, {"nlgrd.x": Path(), "nlgrd.y": Path()}, "nlgrd.z") == {"nlgrd.y"}


def test_no_import_cycles():
    assert _cycles(import_graph()) == []


def _package(module: str) -> str:
    parts = module.split(".")
    return parts[1] if len(parts) > 2 or (len(parts) == 2 and (PACKAGE / parts[1]).is_dir()) else parts[-1]


def test_subpackages_import_only_lower_layers():
    bad = []
    for mod, deps in import_graph().items():
        pkg = _package(mod)
        if pkg not in ALLOWED:
            continue
        for dep in deps:
            other = _package(dep) if dep != "nlgrd" else "nlgrd"
            if other not in (pkg, "errors", "cache", "threads") and other not in ALLOWED[pkg]:
                bad.append(f"{mod} imports {dep}")
    assert bad == []


@pytest.mark.parametrize("module", sorted(_modules()))
def test_module_size(module):
    """No module over MAX_LINES lines (docs/style.md: a module is one concept), unless it is
    one concept reviewed and listed in LONG_MODULES with its reason and a ceiling (a split
    along other lines would cut the concept or its comments); docs/conventions.md."""
    n = len(_modules()[module].read_text(encoding="utf-8").splitlines())
    limit, _reason = LONG_MODULES.get(module, (MAX_LINES, ""))
    assert n <= limit, f"{module}: {n} lines"


def test_no_cache_in_module_globals():
    """An empty container or an lru_cache at module level would be a cache shared by every
    model; caches live on the objects that own them (bounded). Non-empty literal tables
    are constants."""
    bad = []
    for mod, path in _modules().items():
        for node in ast.parse(path.read_text(encoding="utf-8")).body:
            value = node.value if isinstance(node, ast.Assign | ast.AnnAssign) else None
            empty = isinstance(value, ast.Dict) and not value.keys
            empty |= isinstance(value, ast.List | ast.Set) and not value.elts
            empty |= isinstance(value, ast.Call) and ast.unparse(value.func).split(".")[-1] in (
                "dict",
                "list",
                "set",
                "OrderedDict",
                "defaultdict",
            )
            if empty:
                bad.append(f"{mod}: line {node.lineno}")
            if isinstance(node, ast.FunctionDef):
                bad += [f"{mod}.{node.name}" for d in node.decorator_list if "cache" in ast.unparse(d)]
    assert bad == []

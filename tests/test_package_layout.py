"""The package layout (docs/conventions.md, "Package layout"): subpackages by concept, the
layers of the packages and of the subpackages of ``nlgrd.nonlinear``, no import cycles, a
size hint for modules, no caches in module globals.

The import graph is read from the source (every ``import``/``from`` statement, also those
inside functions, which are cycles deferred to run time). No cycle is allowed, counting
imports under ``if TYPE_CHECKING:`` too. For the layers between packages those are
annotations only and do not count; inside ``nlgrd.nonlinear`` they count too (a layer that
names a higher layer's class in an annotation is read as depending on it).
"""

from __future__ import annotations

import ast
from pathlib import Path

PACKAGE = Path(__file__).resolve().parents[1] / "nlgrd"
#: A size hint, not a rule: a module is one concept, and a concept is never split, nor its
#: comments cut, to meet a count. A module above SIZE_HINT lines is listed in LONG_MODULES
#: with a ceiling and the reason it is one concept (reviewed).
SIZE_HINT = 800
#: Modules reviewed as one concept above SIZE_HINT: {module: (ceiling, why it is one concept)}.
LONG_MODULES: dict[str, tuple[int, str]] = {
    "nlgrd.nonlinear.reduction.link_reduction": (
        840,
        "one class, LinkReceptance: κ_k, F_k, their ω-derivatives and the recovery of any DOF"
        " through one of four interchangeable solution strategies that share its caches and"
        " its choice between them; splitting by strategy would cut each method in four",
    ),
}

#: What each subpackage may import from nlgrd (besides itself and the top-level helpers
#: nlgrd.errors, nlgrd.cache, nlgrd.threads and nlgrd.units): the
#: layers, lowest first. Plotting draws results and imports no analysis module; the command
#: line is the top layer (:func:`test_the_command_line_is_the_top_layer`).
ALLOWED = {
    "rotor": {"plotting"},
    "gear": {"plotting"},
    "plotting": set(),
    "nonlinear": {"rotor", "gear", "plotting"},
    "timedomain": {"rotor", "gear", "nonlinear", "plotting"},  # plotting: RampResult.plot
    "io": {"rotor", "gear", "nonlinear", "plotting"},  # plotting: the linear analyses' figures
    "studies": {"rotor", "gear", "nonlinear", "timedomain", "io", "plotting", "analyses", "nlgrd"},
    "cli": {"rotor", "gear", "nonlinear", "timedomain", "io", "plotting", "analyses", "studies", "nlgrd"},
}


#: The subpackages of nlgrd.nonlinear, lowest first, and what each may import from the
#: others (besides itself): every layer below it. Counted on the whole import graph,
#: imports inside functions and under ``if TYPE_CHECKING:`` included. docs/conventions.md,
#: "Layers inside nlgrd.nonlinear".
NONLINEAR_LAYERS = (
    "fourier",
    "laws",
    "results",
    "links",
    "reduction",
    "hb",
    "stability",
    "tracing",
    "models",
)
NONLINEAR_ALLOWED = {
    "fourier": set(),
    "laws": {"fourier"},
    "results": {"fourier", "laws"},
    "links": {"fourier", "laws", "results"},
    "reduction": {"fourier", "laws", "results", "links"},
    "hb": {"fourier", "laws", "results", "links", "reduction"},
    "stability": {"fourier", "laws", "results", "links", "reduction", "hb"},
    "tracing": {"fourier", "laws", "results", "links", "reduction", "hb", "stability"},
    "models": {"fourier", "laws", "results", "links", "reduction", "hb", "stability", "tracing"},
}
#: Imports against the layers above, each with its reason: {(importer, imported): why}.
NONLINEAR_EXCEPTIONS: dict[tuple[str, str], str] = {}


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


def _imports(tree: ast.AST, modules: dict[str, Path], own: str, type_checking: bool = False) -> set[str]:
    """nlgrd modules imported anywhere in ``tree``; those in ``if TYPE_CHECKING:`` blocks
    only with ``type_checking``."""
    out: set[str] = set()

    def visit(node):
        if isinstance(node, ast.If) and _is_type_checking(node) and not type_checking:
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


def import_graph(type_checking: bool = False) -> dict[str, set[str]]:
    mods = _modules()
    return {
        m: _imports(ast.parse(p.read_text(encoding="utf-8")), mods, m, type_checking) for m, p in mods.items()
    }


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
    """No cycle in the whole package, annotation-only (``TYPE_CHECKING``) imports counted
    too (the brief: "no import cycles, type-only ones included")."""
    assert _cycles(import_graph()) == []
    assert _cycles(import_graph(type_checking=True)) == []


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
            if other not in (pkg, "errors", "cache", "threads", "units") and other not in ALLOWED[pkg]:
                bad.append(f"{mod} imports {dep}")
    assert bad == []


def test_the_command_line_is_the_top_layer():
    """``nlgrd.cli`` is one package, and nothing in nlgrd imports it but itself, counting
    imports inside functions and under ``if TYPE_CHECKING:``: the library (the report job
    too) calls the library, never a command."""
    assert (PACKAGE / "cli" / "__init__.py").is_file()
    assert sorted(p.name for p in PACKAGE.glob("cli*.py")) == []
    bad = [
        f"{mod} imports {dep}"
        for mod, deps in import_graph(type_checking=True).items()
        for dep in deps
        if _package(dep) == "cli" and _package(mod) != "cli"
    ]
    assert bad == []


def test_nonlinear_layers_are_an_order():
    """Each layer may import exactly the layers below it: the table is an order."""
    assert tuple(NONLINEAR_ALLOWED) == NONLINEAR_LAYERS
    for i, layer in enumerate(NONLINEAR_LAYERS):
        assert NONLINEAR_ALLOWED[layer] == set(NONLINEAR_LAYERS[:i])
    on_disk = {p.name for p in (PACKAGE / "nonlinear").iterdir() if (p / "__init__.py").is_file()}
    assert on_disk == set(NONLINEAR_LAYERS)
    assert [p.name for p in (PACKAGE / "nonlinear").glob("*.py")] == ["__init__.py"]


def _nonlinear_layer(module: str) -> str | None:
    parts = module.split(".")
    return parts[2] if len(parts) > 3 and parts[1] == "nonlinear" else None


def test_nonlinear_subpackages_import_only_lower_layers():
    bad = []
    for mod, deps in import_graph(type_checking=True).items():
        layer = _nonlinear_layer(mod)
        if layer is None:
            continue
        for dep in deps:
            other = _nonlinear_layer(dep)
            if other in (None, layer) or other in NONLINEAR_ALLOWED[layer]:
                continue
            if (mod, dep) not in NONLINEAR_EXCEPTIONS:
                bad.append(f"{mod} imports {dep}")
    assert bad == []


def test_no_import_cycles_inside_nonlinear_counting_annotations():
    graph = import_graph(type_checking=True)
    inside = {m: {d for d in ds if d.startswith("nlgrd.nonlinear")} for m, ds in graph.items()}
    assert _cycles({m: ds for m, ds in inside.items() if m.startswith("nlgrd.nonlinear")}) == []


def test_nonlinear_init_modules_are_docstrings_only():
    """No re-exports: a subpackage's ``__init__`` is its one-line docstring."""
    for init in (PACKAGE / "nonlinear").rglob("__init__.py"):
        body = ast.parse(init.read_text(encoding="utf-8")).body
        assert len(body) == 1 and isinstance(body[0], ast.Expr), init


def test_long_modules_are_listed():
    """A module above SIZE_HINT lines is listed in LONG_MODULES with its reason and a
    ceiling; a listed module stays under its ceiling and above the hint (else the entry goes)."""
    sizes = {m: len(p.read_text(encoding="utf-8").splitlines()) for m, p in _modules().items()}
    unlisted = [f"{m}: {n} lines" for m, n in sizes.items() if n > SIZE_HINT and m not in LONG_MODULES]
    over = [f"{m}: {sizes[m]} > {c}" for m, (c, _why) in LONG_MODULES.items() if sizes.get(m, 0) > c]
    stale = [m for m in LONG_MODULES if sizes.get(m, 0) <= SIZE_HINT]
    assert (unlisted, over, stale) == ([], [], [])


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

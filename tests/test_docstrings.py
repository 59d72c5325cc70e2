"""Public docstrings and signatures against docs/conventions.md.

Every public module-level function and class of nlgrd: a numpydoc docstring (a
``Parameters`` section naming every parameter, ``Returns`` when the function returns a
value, ``Parameters`` or ``Attributes`` for a class); a parameter named in the
conventions' names table documented with that table's unit in brackets; no parameter of
a public function or method under a name the table rules out.
"""

from __future__ import annotations

import ast
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "nlgrd"
CONVENTIONS = ROOT / "docs" / "conventions.md"


def names_table() -> dict[str, tuple[str, set[str]]]:
    """name -> (unit, names ruled out) from the table between the names-table markers."""
    text = CONVENTIONS.read_text(encoding="utf-8")
    block = text.split("<!-- names-table -->", 1)[1].split("<!-- end names-table -->", 1)[0]
    out = {}
    for line in block.splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if len(cells) != 4 or not cells[0].startswith("`"):
            continue
        name = cells[0].strip("`")
        banned = set(re.findall(r"`([^`]+)`", cells[3]))
        out[name] = (cells[2], banned)
    return out


def sections(doc: str) -> dict[str, list[str]]:
    """numpydoc sections of a cleaned docstring: title -> its lines."""
    lines = doc.splitlines()
    out: dict[str, list[str]] = {}
    title = None
    i = 0
    while i < len(lines):
        if i + 1 < len(lines) and lines[i].strip() and set(lines[i + 1].strip()) == {"-"}:
            title = lines[i].strip()
            out[title] = []
            i += 2
            continue
        if title is not None:
            out[title].append(lines[i])
        i += 1
    return out


def entries(lines: list[str]) -> dict[str, str]:
    """Entries of a Parameters/Attributes section: each name -> its type line and description."""
    groups: list[tuple[list[str], list[str]]] = []
    for line in lines:
        if line and not line[0].isspace():
            head = line.split(" : ", 1)[0].rstrip(":").strip()
            groups.append(([n.strip().lstrip("*") for n in head.split(",")], [line]))
        elif groups:
            groups[-1][1].append(line)
    return {name: "\n".join(text) for names, text in groups for name in names}


def public_items():
    """(module, node) of every public module-level function and class."""
    for path in sorted(PACKAGE.rglob("*.py")):
        mod = ".".join(path.relative_to(ROOT).with_suffix("").parts)
        tree = ast.parse(path.read_text(encoding="utf-8"))
        for node in tree.body:
            if isinstance(node, ast.FunctionDef | ast.ClassDef) and not node.name.startswith("_"):
                yield mod, node


def parameters(fn: ast.FunctionDef) -> list[str]:
    a = fn.args
    names = [x.arg for x in a.posonlyargs + a.args + a.kwonlyargs]
    return [n for n in names if n not in ("self", "cls")]


def returns_value(fn: ast.FunctionDef) -> bool:
    ann = fn.returns
    if ann is not None:
        return not (isinstance(ann, ast.Constant) and ann.value is None)
    return any(
        isinstance(n, ast.Return) and n.value is not None
        for n in ast.walk(fn)
        if not isinstance(n, ast.FunctionDef | ast.Lambda)
    )


def check(node: ast.FunctionDef | ast.ClassDef, table) -> list[str]:
    """What ``node``'s docstring and signature miss (empty when it follows the conventions)."""
    doc = ast.get_docstring(node)
    if not doc:
        return ["no docstring"]
    secs = sections(doc)
    problems = []
    if isinstance(node, ast.ClassDef):
        is_error = any(ast.unparse(b).endswith(("Error", "Exception", "Warning")) for b in node.bases)
        if not is_error and not ({"Parameters", "Attributes"} & set(secs)):
            problems.append("no Parameters or Attributes section")
        documented = entries(secs.get("Parameters", []) + secs.get("Attributes", []))
    else:
        params = parameters(node)
        documented = entries(secs.get("Parameters", []))
        if params and "Parameters" not in secs:
            problems.append("no Parameters section")
        elif params:
            missing = [p for p in params if p not in documented]
            if missing:
                problems.append(f"parameters not documented: {', '.join(missing)}")
        if returns_value(node) and not ({"Returns", "Yields"} & set(secs)):
            problems.append("no Returns section")
    for name, text in documented.items():
        unit = table.get(name, ("-", set()))[0]
        if unit not in ("-", "") and f"[{unit}]" not in text:
            problems.append(f"{name}: unit [{unit}] not stated")
    return problems


def banned_parameters(table) -> list[str]:
    """Public functions and methods with a parameter name the conventions rule out."""
    banned = {b: name for name, (_, bs) in table.items() for b in bs}
    out = []
    for mod, node in public_items():
        fns = (
            [node]
            if isinstance(node, ast.FunctionDef)
            else [m for m in node.body if isinstance(m, ast.FunctionDef) and not m.name.startswith("_")]
        )
        for fn in fns:
            for p in parameters(fn):
                if p in banned:
                    out.append(f"{mod}.{fn.name}({p}): use {banned[p]!r}")
    return out


def test_conventions_table_is_read():
    table = names_table()
    assert {"omega", "omegas", "H", "tol", "rtol"} <= set(table)
    assert table["omega"][0] == "rad/s" and "w" in table["omega"][1]


def test_the_checks_can_fail():
    """A function without sections, a missing unit and a banned name are all reported."""
    table = names_table()
    tree = ast.parse(
        "def f(omega, H):\n"
        "    '''Summary.\n\n    Parameters\n    ----------\n    omega : float\n        Frequency.\n"
        "    H : int\n        Harmonics.\n\n    Returns\n    -------\n    float\n    '''\n"
        "    return 1.0\n"
        "def g(x):\n    '''No sections.'''\n    return x\n"
    )
    f, g = tree.body
    assert check(f, table) == ["omega: unit [rad/s] not stated"]
    assert check(g, table) == ["no Parameters section", "no Returns section"]


def test_no_banned_parameter_names():
    assert banned_parameters(names_table()) == []


@pytest.mark.parametrize(
    "package", sorted(p.name for p in PACKAGE.iterdir() if p.is_dir() and p.name[0] != "_")
)
def test_public_docstrings(package):
    table = names_table()
    bad = [
        f"{mod}.{node.name}: {'; '.join(problems)}"
        for mod, node in public_items()
        if mod.split(".")[1] == package and (problems := check(node, table))
    ]
    assert bad == [], "\n".join(bad)


def test_top_level_docstrings():
    table = names_table()
    bad = [
        f"{mod}.{node.name}: {'; '.join(problems)}"
        for mod, node in public_items()
        if mod.count(".") == 1 and (problems := check(node, table))
    ]
    assert bad == [], "\n".join(bad)

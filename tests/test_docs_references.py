"""Every dotted ``nlgrd.…`` name in the documentation and the docstrings resolves: a module,
or an attribute of one (a renamed or moved function leaves no stale reference behind)."""

from __future__ import annotations

import importlib
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DOCS = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md")), ROOT / "benchmarks" / "README.md"]
SOURCES = [*sorted((ROOT / "nlgrd").rglob("*.py")), ROOT / "benchmarks" / "bench_nonlinear.py"]
NAME = re.compile(r"\bnlgrd(?:\.[A-Za-z_][A-Za-z0-9_]*)+")


def resolves(name: str) -> bool:
    """The longest importable module prefix of ``name``, then attributes (dataclass fields
    count: they are attributes of instances)."""
    parts = name.split(".")
    for i in range(len(parts), 0, -1):
        try:
            obj = importlib.import_module(".".join(parts[:i]))
        except ImportError:
            continue
        for part in parts[i:]:
            if part in getattr(obj, "__dataclass_fields__", {}):
                return True
            if not hasattr(obj, part):
                return False
            obj = getattr(obj, part)
        return True
    return False


def stale(paths) -> list[str]:
    out = []
    for path in paths:
        for m in NAME.finditer(path.read_text(encoding="utf-8")):
            name = m.group(0).rstrip(".")
            if not name.endswith((".py", ".toml")) and not resolves(name):
                out.append(f"{path.relative_to(ROOT)}: {name}")
    return sorted(set(out))


def test_resolver_rejects_a_stale_name():
    assert resolves("nlgrd.nonlinear.tracing.sweep.sweep") and resolves(
        "nlgrd.nonlinear.results.sweep_results.SweepResult.omega"
    )
    assert not resolves("nlgrd.nonlinear.tracing.sweep.no_such_function") and not resolves(
        "nlgrd.no_such_analysis"
    )


@pytest.mark.parametrize("kind", ["docs", "sources"])
def test_no_stale_references(kind):
    assert stale(DOCS if kind == "docs" else SOURCES) == []

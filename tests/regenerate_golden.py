"""Regenerate the golden curves of tests/test_notebooks.py.

    .venv/bin/python tests/regenerate_golden.py [NAME ...]

Runs each case-study notebook (all, or those named) exactly as the test does (fast mode,
the same SYNTHETIC measured data sets) and replaces ``tests/golden/<notebook>/`` with its
golden files (``GOLDEN_FILES``: linear, branch-robust results). Review the diff before
committing: a golden should change only when the library or the notebook changed on
purpose, and ``test_linear_goldens_match_a_refined_mesh`` must confirm the new numbers.
"""

from __future__ import annotations

import shutil
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from test_notebooks import GOLDEN, GOLDEN_FILES, NAMES, run_fast  # noqa: E402


def main(names: list[str]) -> int:
    for name in names or NAMES:
        if name not in NAMES:
            print(f"unknown notebook {name!r}; one of {', '.join(NAMES)}", file=sys.stderr)
            return 2
        print(f"{name}: running in fast mode ...", flush=True)
        with tempfile.TemporaryDirectory() as tmp:
            out = run_fast(name, Path(tmp) / "out")
            target = GOLDEN / name
            staged = GOLDEN / f".{name}.new"
            if staged.exists():
                shutil.rmtree(staged)
            staged.mkdir(parents=True)
            for file in GOLDEN_FILES[name]:
                shutil.copy2(out / file, staged / file)
            if target.exists():
                shutil.rmtree(target)
            staged.rename(target)
        print(f"  -> {target.relative_to(GOLDEN.parent.parent)}: {len(list(target.glob('*.csv')))} CSV files")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))

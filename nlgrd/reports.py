"""The main job: build every report into ``reports/`` (``python -m nlgrd.reports``).

For each example model in ``data/models/``: the table and shapes of its modes and its
Campbell diagram. Case-study notebooks, when present in ``notebooks/``, are executed
with papermill into ``reports/`` as well.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

from nlgrd.cli import main as cli_main

ROOT = Path(__file__).resolve().parent.parent


def build_model_reports(out: Path) -> None:
    """Modes and Campbell diagram of each model in data/models/."""
    models = sorted((ROOT / "data" / "models").glob("*.toml"))
    for i, model in enumerate(models, 1):
        print(f"[{i}/{len(models)}] {model.name}: modes and Campbell diagram", flush=True)
        target = out / "models"
        for argv in (
            ["modes", str(model), "--out", str(target)],
            ["campbell", str(model), "--rpm", "0:15000:61", "--orders", "1", "--out", str(target)],
        ):
            status = cli_main(argv)
            if status:
                raise SystemExit(status)


def main() -> int:
    """Build all reports; returns the exit status."""
    out = ROOT / "reports"
    out.mkdir(exist_ok=True)
    t0 = time.perf_counter()
    build_model_reports(out)
    print(f"reports written to {out} in {time.perf_counter() - t0:.1f} s", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())

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


def build_gear_reports(out: Path) -> None:
    """LSTE of the geared example and the tip-relief sweep of Kubo's gears."""
    import matplotlib

    matplotlib.use("Agg")
    import numpy as np

    from nlgrd.gear_geometry import GearGeometry
    from nlgrd.transmission_error import single_pair_deflection, tip_relief_sweep

    target = out / "gears"
    for model in sorted((ROOT / "data" / "models").glob("*.toml")):
        text = model.read_text()
        if "[[gear_pairs]]" in text:
            print(f"{model.name}: loaded static transmission error", flush=True)
            if cli_main(["lste", str(model), "--out", str(target)]):
                raise SystemExit(2)
    print("Kubo's gears: tip-relief sweep", flush=True)
    geo = GearGeometry(25, 25, 4e-3, 15e-3)
    load = 2295.0
    deflection = single_pair_deflection(geo, load)
    sweep = tip_relief_sweep(geo, load, np.linspace(0, 2 * deflection, 41))
    ax = sweep.plot(design_deflection=deflection)
    ax.figure.tight_layout()
    ax.figure.savefig(target / "kubo_tip_relief_sweep.png", dpi=100)
    sweep.to_frame().to_csv(target / "kubo_tip_relief_sweep.csv", index=False)


def main() -> int:
    """Build all reports; returns the exit status."""
    out = ROOT / "reports"
    out.mkdir(exist_ok=True)
    t0 = time.perf_counter()
    build_model_reports(out)
    build_gear_reports(out)
    print(f"reports written to {out} in {time.perf_counter() - t0:.1f} s", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""Per-point cost of harmonic-balance sweeps with 1, 2 and 3 nonlinear links (issue 11).

Run from the repository root::

    .venv/bin/python benchmarks/bench_links.py

The Jeffcott rotor of tests/test_bearing_clearance.py (30 DOFs, unbalance, base = shaft
speed) with a radial clearance at one bearing (1 link, 2 coordinates), at both bearings
(2 links, 4 coordinates), and at both bearings plus a retainer ring around the disk (3
links, 6 coordinates); up sweeps of 20 points from 15 to 24 Hz, below the first contact
(Floquet on one contact state), and of 32 points from 15 to 30 Hz, 13 of them with the
journal of B on its clearance (Floquet on the 256 AFT cells of the period); H = 7, one
BLAS thread.
Figures and machine in benchmarks/README.md.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np
from threadpoolctl import threadpool_limits

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))

import test_bearing_clearance as jeff  # noqa: E402

from nlgrd.nonlinear.links.contract import BearingClearance  # noqa: E402
from nlgrd.nonlinear.models.link_model import Unbalance, build_link_model, link_sweep  # noqa: E402


def models():
    """(label, model) for 1, 2 and 3 clearance links."""
    system = jeff.jeffcott()
    unb = [Unbalance(0, 2, jeff.DISK.mass * jeff.ECCENTRICITY)]
    b4 = BearingClearance("B", 0, 4, clearance=30e-6, stiffness=jeff.K_CONTACT)
    b0 = BearingClearance("A", 0, 0, clearance=30e-6, stiffness=jeff.K_CONTACT)
    ring = BearingClearance("ring", 0, 2, clearance=2e-3, stiffness=jeff.K_CONTACT)
    for links in ([b4], [b4, b0], [b4, b0, ring]):
        label = f"{len(links)} link(s), {2 * len(links)} coordinates"
        yield label, build_link_model(system, links, unbalance=unb)


def main() -> None:
    grids = {
        "15-24 Hz, no contact": 2 * np.pi * np.linspace(15.0, 24.0, 20),
        "15-30 Hz, B on its clearance above 24 Hz": 2 * np.pi * np.linspace(15.0, 30.0, 32),
    }
    with threadpool_limits(1):
        for label, model in models():
            link_sweep(model, grids["15-24 Hz, no contact"][:2], H=7, directions="up", period=1)  # warm-up
            for name, omegas in grids.items():
                t0 = time.perf_counter()
                res = link_sweep(model, omegas, H=7, directions="up", period=1).result
                per = 1e3 * (time.perf_counter() - t0) / omegas.size
                ok = int(np.sum(res.converged & res.stable.astype(bool)))
                print(f"{label}, {name}: {per:.1f} ms per point ({ok}/{omegas.size} stable)", flush=True)


if __name__ == "__main__":
    main()

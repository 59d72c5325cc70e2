"""Recount (issue 35 item 1): do the stability columns of every row of K&B's period-"auto"
sweeps belong to the orbit the row answers? (The sweeps of the link engine: ``link_sweep``
as ``nlgrd.sweep`` runs it.)

For each converged row with a settled verdict, the Floquet multipliers of the row's own
orbit (its stored harmonics) are recomputed on the model of the sweep's base (the
period-2 model on ω/2 when some point has period 2: a period-1 orbit's multipliers over
2T are μ², so max |μ| is the square root there) and compared with the row's
``floquet_max``. The written verdict may come from a higher H (verdicts agree between
rungs within 1e-2, ``nlgrd.nonlinear.stability.verdicts.MULTIPLIER_RTOL``), so a row is
counted as carrying another orbit's multiplier beyond 2e-2. The synthetic check of the
same property is tests/test_verdicts.py::test_merged_rows_carry_the_multipliers_of_their_own_orbit.

    .venv/bin/python tests/recount_merged_multipliers.py [--full]

Fast (notebook 02's fast grid, 60 points per direction; the parametric windows and the
main sweep as given): 889 s at nice 15 on the shared 2-core machine (load 10-14),
2026-12-06; result: 0 of 144 rows (the 2/3 window on the ω/2 base: 10 period-1 rows
beside 2 period-2 rows, largest difference 5e-15; the main sweep on the ω/2 base, 120
rows, 1.2e-3). On the link engine: 697 s at nice 15 (load 6-9), 2026-12-07; 0 of 144
rows (the 2/3 window 1.8e-15, the 1/4 window on the ω base 7.2e-3, the main sweep
1.15e-3).
"""

from __future__ import annotations

import sys
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

from nlgrd.io.model_file import load_model
from nlgrd.nonlinear.models.link_model import build_link_model, link_sweep, period_model
from nlgrd.nonlinear.stability.floquet import floquet_multipliers
from nlgrd.rotor.modal import gear_pair_mode

ROOT = Path(__file__).resolve().parent.parent
#: Twice the agreement of two rungs' verdicts (verdicts.MULTIPLIER_RTOL).
RTOL = 2e-2
#: Notebook 02's windows of the parametric sweep (x gear-pair mode).
WINDOWS = ((0.25, 0.37), (0.60, 0.72))


def recount(link_model, result, label: str) -> int:
    """Rows of ``result`` (a :class:`LinkSweepResult` of ``link_model``) whose floquet_max
    is not their own orbit's; printed, returned."""
    m = result.result
    base = int(m.base)
    model = (period_model(link_model, base) if base > 1 else link_model).reduced
    rows = [
        i
        for i in range(len(m))
        if m.converged[i] and np.isfinite(m.floquet_max[i]) and m.verdict_converged[i]
    ]
    bad, worst = [], 0.0
    for i in rows:
        w = float(m.omega[i]) / base
        mu = floquet_multipliers(model.linear_state_space(w), model.nonlinearities, m.harmonics[i], w)
        own = float(np.max(np.abs(mu))) ** (int(m.period[i]) / base)
        rel = abs(own / m.floquet_max[i] - 1)
        worst = max(worst, rel)
        if rel > RTOL:
            bad.append(
                (
                    str(m.direction[i]),
                    float(m.omega[i] / 2 / np.pi),
                    int(m.period[i]),
                    float(m.floquet_max[i]),
                    own,
                )
            )
    p1_on_2 = int(np.sum((m.period == 1)[rows])) if base == 2 else 0
    print(
        f"{label}: base {base}, {len(rows)} rows with multipliers ({p1_on_2} period-1 rows on the ω/2 base, "
        f"{int((m.period == 2).sum())} period-2 rows); not their own orbit's (> {RTOL:g}): {len(bad)}; "
        f"largest relative difference {worst:.2e}",
        flush=True,
    )
    for b in bad:
        print("   ", b)
    return len(bad)


def main(full: bool) -> int:
    s = load_model(ROOT / "data" / "case_studies" / "kahraman_blankenship.toml")
    freqs = np.linspace(800.0, 6000.0, 300 if full else 60)
    f_gp = gear_pair_mode(s)[0]
    s_par = replace(s, gear_pairs=(replace(s.gear_pairs[0], stiffness_variation="load_sharing"),))
    t0, total = time.perf_counter(), 0
    for lo, hi in WINDOWS:
        seg = freqs[(freqs >= lo * f_gp) & (freqs <= hi * f_gp)]
        lm = build_link_model(s_par)
        r = link_sweep(lm, 2 * np.pi * seg, directions="both", period="auto")
        total += recount(lm, r, f"parametric k, window {lo}-{hi} x f_gp")
    lm = build_link_model(s)
    r = link_sweep(lm, 2 * np.pi * freqs, directions="both", period="auto")
    total += recount(lm, r, "constant k_h, as given (main sweep)")
    print(f"rows not of their own orbit: {total} ({time.perf_counter() - t0:.0f} s)")
    return total


if __name__ == "__main__":
    sys.exit(1 if main("--full" in sys.argv) else 0)

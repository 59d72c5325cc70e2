"""Reference for the quasi-periodic harmonic balance on a model with two active links: Kubo's
rig (data/case_studies/kubo.toml) with a radial rub ring of 0.5 um clearance and
5e8 N/m contact stiffness at the gear's node (:data:`RUB`; the gear's centre moves by up
to 0.9 um on the torus, so the ring is touched 14-19 % of the time with up to 200 N),
a link model of two nonsmooth links (the mesh's backlash and the rub). Time integration of
the same link model (HHT-α, :class:`nlgrd.timedomain.links.LinkIntegrator`, 512 steps per
mesh period) at constant speed in its Neimark-Sacker band, against the torus of
:func:`nlgrd.nonlinear.tracing.torus_sweep.torus_sweep` with
:class:`nlgrd.nonlinear.tracing.link_torus.LinkTorus` (H₁ 13, H₂ 4, checked at (17, 6)).

Each run starts on the unstable periodic orbit (the link sweep's, H 13), integrates
``TRANSIENT`` mesh periods on the period map (discarded), then ``BLOCKS`` blocks of
``SPACING`` periods, the last period of each block recorded step by step: the RMS of δ
(alternating part), the largest mesh force W = k_h f(δ - e) + c_m (δ' - e'), the rub's
largest contact force and contact fraction. δ at the start of every period (the Poincaré
section θ₁ = 0) gives the rotation number as in benchmarks/torus_kubo_reference.py, and
the secondary frequency.

Run (one at a time, one thread): ``OPENBLAS_NUM_THREADS=1 python benchmarks/torus_link_reference.py``.
Writes benchmarks/torus_link_reference.csv (speeds, time-domain and torus figures, their
relative differences, the CPU time of each torus point and of a periodic point).
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np
import pandas as pd

from nlgrd.io.model_file import load_model
from nlgrd.nonlinear.models.link_model import build_link_model, link_sweep
from nlgrd.nonlinear.tracing.link_torus import LinkTorus, torus_link_columns
from nlgrd.nonlinear.tracing.torus_sweep import torus_sweep
from nlgrd.timedomain.links import LinkIntegrator, start_from_harmonics

ROOT = Path(__file__).resolve().parent.parent
KUBO = ROOT / "data" / "case_studies" / "kubo.toml"
#: The rub ring at the gear's node (shaft 1, node 2).
RUB = """
[[bearing_clearances]]
name = "rub"
shaft = 1
node = 2
clearance = 5e-7
stiffness = 5e8
"""
RPM = (13775.0, 13825.0, 13875.0)
TRANSIENT, BLOCKS, SPACING, STEPS = 3000, 500, 6, 512


def rotation_number(x: np.ndarray) -> float:
    """Rotation per sample of the Poincaré samples ``x`` in (0, 1/2] [-]."""
    x = x - np.mean(x)
    spec = np.abs(np.fft.rfft(x * np.hanning(x.size)))
    j = 2 + int(np.argmax(spec[2:-1]))
    a, b, c = np.log(spec[j - 1 : j + 2])
    return float((j + 0.5 * (a - c) / (a - 2 * b + c)) / x.size)


def model_file(directory: Path) -> Path:
    """Kubo's model file with the rub ring, written to ``directory``."""
    path = directory / "kubo_rub.toml"
    path.write_text(KUBO.read_text() + RUB)
    return path


def reference(model, omega: float, harmonics: np.ndarray) -> dict:
    """The time-domain statistics at ``omega`` from the periodic orbit ``harmonics``."""
    integ = LinkIntegrator(model, omega, steps_per_period=STEPS)
    H = (harmonics.shape[1] - 1) // 2
    s = integ.start(start_from_harmonics(model, omega, H, harmonics))
    sl = dict(zip((lk.name for lk in model.links), model.receptance.slices, strict=True))
    mesh = next(lk for lk in model.links if lk.name == "mesh0").mesh
    m, r = sl["mesh0"].start, sl["rub"]
    e, de = mesh.lste_samples(STEPS)
    for _ in range(TRANSIENT):
        _, s = integ.period(s)
    d, w, fr, cr, p = [], [], [], [], []
    for _ in range(BLOCKS):
        for _ in range(SPACING - 1):
            y, s = integ.period(s)
            p.append(y[m, 0])
        rec = integ.record(s)
        s = rec.end
        p.append(rec.y[m, 0])
        d.append(rec.y[m])
        w.append(rec.g[m] + mesh.damping * (rec.ydot[m] - omega * de))
        u = rec.y[r]
        fr.append(np.hypot(*rec.g[r]))
        cr.append(np.hypot(*u) > model.links[[lk.name for lk in model.links].index("rub")].clearance)
    d, w, fr, cr, p = (np.concatenate(a) for a in (d, w, fr, cr, [np.asarray(p)]))
    f1 = omega / (2 * np.pi)
    half = d.size // 2
    return {
        "ti_mesh0.dte_rms [m]": float(np.std(d)),
        "ti_mesh0.force_max [N]": float(np.max(w)),
        "ti_rub.force_max [N]": float(np.max(fr)),
        "ti_rub.contact_fraction [-]": float(np.mean(cr)),
        "ti_secondary_frequency [Hz]": rotation_number(p) * f1,
        "ti_dte_rms halves [-]": float(np.std(d[:half]) / np.std(d[half:]) - 1),
        "ti_force_max halves [-]": float(np.max(w[:half]) / np.max(w[half:]) - 1),
    }


def main(argv: list[str]) -> int:
    """The speeds :data:`RPM` (the up sweep), one row each."""
    import tempfile  # noqa: PLC0415

    with tempfile.TemporaryDirectory() as tmp:
        system = load_model(model_file(Path(tmp)))
    model = build_link_model(system)
    omegas = np.array(RPM) * 2 * np.pi / 60 * 25
    t = time.process_time()
    sw = link_sweep(model, omegas, H=13, directions="up", period=1)
    periodic_cost = (time.process_time() - t) / omegas.size
    res = sw.result
    target = LinkTorus(model)
    t = time.process_time()
    tor = torus_sweep(model, omegas, H=13, periodic=res.harmonics, target=target)
    torus_cost = (time.process_time() - t) / omegas.size
    rows = []
    for i, w in enumerate(omegas):
        row = {
            "pinion_speed [rpm]": RPM[i],
            "periodic point CPU [s]": periodic_cost,
            "torus point CPU [s]": torus_cost,
            "floquet_max [-]": float(res.floquet_max[i]),
            "torus_error [-]": float(tor.error[i]),
            "H": 13,
            "H2": 4,
        }
        sol = tor.solutions[i]
        if sol is None:
            rows.append(row)
            continue
        cols = torus_link_columns(model, sol)
        row.update({k: cols[k] for k in ("mesh0.dte_rms [m]", "mesh0.force_max [N]", "rub.force_max [N]")})
        row["rub.contact_fraction [-]"] = cols["rub.contact_fraction [-]"]
        row["secondary_frequency [Hz]"] = sol.secondary / (2 * np.pi)
        t = time.process_time()
        row.update(reference(model, float(w), res.harmonics[i]))
        row["time integration CPU [s]"] = time.process_time() - t
        for q in ("mesh0.dte_rms [m]", "mesh0.force_max [N]", "rub.force_max [N]"):
            row["diff " + q] = row[q] / row["ti_" + q] - 1
        q = "secondary_frequency [Hz]"
        row["diff " + q] = row[q] / row["ti_" + q] - 1
        q = "rub.contact_fraction [-]"
        row["diff " + q] = row[q] - row["ti_" + q]
        rows.append(row)
        print(row, flush=True)
    out = pd.DataFrame(rows)
    out.to_csv(Path(__file__).with_suffix(".csv"), index=False)
    print(out.to_string())
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))

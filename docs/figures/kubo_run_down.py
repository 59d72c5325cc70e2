"""Kubo's main down jump judged by a slow run-down in the time domain (issue 36, item 2).

Draws ``docs/figures/kubo_run_down.png``: the DTE RMS of each mesh cycle of a run-down of
the full FE model (:func:`nlgrd.timedomain.run_down.run_down`, pinion speed ramped
linearly from 10 000 to 5500 rpm at two rates, started on the harmonic-balance down
sweep's orbit at 10 000 rpm) over the harmonic-balance up and down sweeps of the CLI grid
(``nlgrd sweep --rpm 4000:16000:241``) and of notebook 01's grid (300 speeds over
2000-16 000 rpm), H chosen by the error estimate, ``jump="auto"``, on the link engine. Prints the down jumps
(CLI: :meth:`SweepResult.jumps`; notebook: :func:`nlgrd.studies.experimental.resonance_jumps`;
run-down: :meth:`RampResult.jump`) and the run times. 7-13 minutes on one core.

Run from the repository root: ``python docs/figures/kubo_run_down.py``.
"""

from __future__ import annotations

import time
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from nlgrd.io.model_file import load_model  # noqa: E402
from nlgrd.nonlinear.models.link_model import build_link_model, link_sweep  # noqa: E402
from nlgrd.plotting import save_figure  # noqa: E402
from nlgrd.plotting.common import place_legend  # noqa: E402
from nlgrd.plotting.nonlinear import plot_sweep_frame  # noqa: E402
from nlgrd.rotor.modal import gear_pair_mode  # noqa: E402
from nlgrd.studies.experimental import directions_of, resonance_jumps  # noqa: E402
from nlgrd.timedomain.links import start_from_harmonics  # noqa: E402
from nlgrd.timedomain.run_down import run_down  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
RPM = "shaft_speed [rpm]"
DTE = "mesh0.dte_rms [um]"
TOP, BOTTOM = 10000.0, 5500.0  # the ramp [rpm]
RATES = (250.0, 125.0)  # pinion rpm/s
STEPS = 256  # time steps per mesh period at the top speed (the step is fixed)
GRIDS = {"CLI": (4000, 16000, 241), "notebook 01": (2000, 16000, 300)}  # [rpm], as np.linspace


def main() -> None:
    system = load_model(ROOT / "data" / "case_studies" / "kubo.toml")
    n_p = system.gear_pairs[0].geometry.teeth_pinion
    model = build_link_model(system)
    per_rpm = 2 * np.pi / 60 * n_p  # mesh frequency [rad/s] per pinion rpm

    def rpm(omega):
        return float(omega) / per_rpm

    rpm_res = gear_pair_mode(system)[0] * 60 / n_p
    frames, notes = {}, []
    for name, spec in GRIDS.items():
        grid = np.linspace(*spec)
        t = time.time()
        fe = link_sweep(model, grid * per_rpm, H=None, directions="both", jump="auto")
        frames[name] = fe.to_frame()
        frames[name].insert(1, RPM, frames[name]["base_frequency [Hz]"] * 2 * np.pi / per_rpm)
        c = directions_of(frames[name], RPM, DTE)
        down = resonance_jumps(c["up"], c["down"], rpm_res)[1]
        listed = [
            (round(rpm(j.omega_from)), round(rpm(j.omega_to)))
            for j in fe.jumps()
            if j.direction == "down" and 5500 < rpm(j.omega_from) < 10000
        ]
        # the CLI's main down jump: the first listed one where the DTE RMS falls to less than half
        falls = [
            (rpm(j.omega_from), rpm(j.omega_to))
            for j in fe.jumps()
            if j.direction == "down" and j.omega_from < TOP * per_rpm and j.value_to < 0.5 * j.value_from
        ]
        step = grid[1] - grid[0]
        h_text = f"H = {fe.result.H} (harmonics of ω/2 where period 2)"
        print(f"{name} grid (step {step:.1f} rpm), {h_text}, {time.time() - t:.0f} s")
        print(f"  down jumps listed by the CLI between 5500 and 10000 rpm: {listed}")
        if falls:
            print(f"  the first where the DTE RMS falls by half: {falls[0][0]:.0f} -> {falls[0][1]:.0f} rpm")
        if down is not None:
            print(
                "  notebook's main down jump (resonance_jumps): "
                f"{down.omega_from:.0f} -> {down.omega_to:.0f} rpm"
            )
        first = (
            (falls[0] if falls else None)
            if name == "CLI"
            else (down.omega_from, down.omega_to)
            if down
            else None
        )
        if first is not None:
            notes.append(f"HB down jump, {name} grid: {first[0]:.0f} -> {first[1]:.0f} rpm")
    # the run-down starts on the HB down sweep's orbit at the top speed (CLI grid: 10 000 rpm on it)
    fe_top = link_sweep(model, np.linspace(TOP, 16000, 121) * per_rpm, H=13, directions="down").result
    i = int(np.argmin(fe_top.omega))
    state0 = start_from_harmonics(model, fe_top.omega[i], 13, fe_top.harmonics[i])
    ramps = []
    for rate in RATES:
        t = time.time()
        r = run_down(
            model,
            float(fe_top.omega[i]),
            BOTTOM * per_rpm,
            rate * per_rpm,
            state0=state0,
            steps_per_period=STEPS,
        )
        jump = np.nan if r.jump() is None else r.jump() / per_rpm
        print(
            f"run-down at {rate:g} rpm/s ({(TOP - BOTTOM) / rate:.0f} s of rig time, "
            f"dt = {r.dt * 1e6:.3f} us, {STEPS} steps per mesh period at {TOP:.0f} rpm): "
            f"jump at {jump:.0f} rpm, {time.time() - t:.0f} s"
        )
        ramps.append((rate, r, jump))

    fig, ax = plt.subplots(figsize=(9, 5))
    window = (BOTTOM - 300, TOP + 500)
    for k, (name, frame) in enumerate(frames.items()):
        part = frame[(frame[RPM] >= window[0]) & (frame[RPM] <= window[1])]
        plot_sweep_frame(part, RPM, DTE, ax=ax, label=f"HB, {name} grid", series=k, ms=2.5 + k, lw=0.6)
    rate, r, jump = ramps[-1]
    r.plot(ax=ax, label=f"run-down, {rate:g} rpm/s")
    ax.text(
        0.42,
        0.98,
        "\n".join(
            notes + ["run-down jump: " + ", ".join(f"{j:.0f} rpm at {a:g} rpm/s" for a, _, j in ramps)]
        ),
        transform=ax.transAxes,
        va="top",
        fontsize=8,
    )
    ax.set_xlim(*window)
    ax.set_title("Kubo's rig: the main down jump, harmonic balance against a slow run-down (full FE model)")
    place_legend(ax, fontsize=7)
    save_figure(fig, ROOT / "docs" / "figures" / "kubo_run_down.png", dpi=130)


if __name__ == "__main__":
    main()

"""Time integration of the full geared finite-element model, the independent reference
of its harmonic balance (:class:`nlgrd.nonlinear.geared.GearedModel`): one frequency
(:func:`time_response`) and sweeps, each point continuing from the last
(:func:`time_sweep`).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import pandas as pd
from numpy.typing import NDArray

from nlgrd.errors import ModelError
from nlgrd.nonlinear.geared import GearedModel
from nlgrd.timedomain.integrator import integrate_fe


def time_response(
    model: GearedModel,
    omega: float,
    *,
    steps_per_period: int = 512,
    tol: float = 1e-6,
    state0: tuple | None = None,
    store_dofs: bool = False,
):
    """Direct time integration of the full FE model with the nonlinear mesh at mesh frequency ``omega``.

    The same equations as the harmonic balance (M, D(Ω) with c_m w wᵀ, K(Ω) without k_h,
    static torques, LSTE), integrated by :func:`nlgrd.timedomain.integrator.integrate_fe` (HHT-α)
    to a periodic steady state. Hysteretic damping has no time-domain form and must be
    absent. Returns :class:`nlgrd.timedomain.integrator.FETimeResponse`.
    """
    lm = model.receptance.model
    if lm.hysteretic_parts:
        raise ModelError(
            "loss_factor", "hysteretic shaft damping has no time-domain form; use viscous damping"
        )
    speed = model.receptance.speed(omega)
    return integrate_fe(
        lm.M,
        lm.damping(speed),
        lm.stiffness(speed),
        model.receptance.W[:, 0],
        model.mesh,
        model.receptance.static_force,
        float(omega),
        steps_per_period=steps_per_period,
        tol=tol,
        state0=state0,
        store_dofs=store_dofs,
    )


def time_sweep(
    model: GearedModel,
    mesh_frequencies: NDArray,
    directions: str = "both",
    *,
    steps_per_period: int = 256,
    tol: float = 1e-4,
    progress: Callable[[int, int], None] | None = None,
) -> pd.DataFrame:
    """Time-domain up and/or down sweep of the full FE model, each point continuing from the last.

    The independent reference for :func:`geared_sweep`: the same equations integrated
    by HHT-α (:func:`time_response`) to a periodic steady state at every frequency,
    starting from the final state of the previous frequency, so the sweep stays on its
    branch and jumps where it must; the down sweep starts where the up sweep ended.
    Returns a frame with "mesh_frequency [Hz]",
    "direction", "converged", "periods", "dte_rms [um]", "dslr [-]",
    "contact_loss_fraction [-]" and "back_contact".
    """
    omegas = np.sort(np.asarray(mesh_frequencies, dtype=float))
    runs = {"up": [omegas], "down": [omegas[::-1]], "both": [omegas, omegas[::-1]]}[directions]
    names = {"up": ["up"], "down": ["down"], "both": ["up", "down"]}[directions]
    rows = []
    total = sum(len(r) for r in runs)
    state = None
    for name, order in zip(names, runs, strict=True):
        for w in order:
            tr = time_response(model, w, steps_per_period=steps_per_period, tol=tol, state0=state)
            state = tr.state
            met = tr.metrics(model.mesh)
            rows.append(
                {
                    "mesh_frequency [Hz]": w / (2 * np.pi),
                    "direction": name,
                    "converged": bool(tr.converged),
                    "periods": tr.periods,
                    "dte_rms [um]": met.dte_rms * 1e6,
                    "dslr [-]": met.dslr,
                    "contact_loss_fraction [-]": met.contact_loss_fraction,
                    "back_contact": bool(met.back_contact),
                }
            )
            if progress:
                progress(len(rows), total)
    return pd.DataFrame(rows)

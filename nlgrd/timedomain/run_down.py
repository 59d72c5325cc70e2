"""Time integration of the full FE model under a speed ramp: a rig's slow run-up or
run-down, the independent judge of which branch a slow sweep follows through a jump.

The equations are those of the link model (:func:`nlgrd.analyses.model`; its harmonic
balance's: M q'' + D(Ω) q' + K(Ω) q + P g(Pᵀ q, θ) = f(t), any links: gear meshes,
bearing clearances), with the base frequency ω(t) = ω_0 - r t ramped linearly and the
phase its integral, θ(t) = ω_0 t - r t²/2: each mesh's LSTE e(θ(t)) and its rate
e' = ω(t) de/dθ, and an unbalance m e at the shaft angle φ = s θ (s its harmonic of the
base) with its force m e (φ'² radially, φ'' tangentially), follow the speed as they do on
a rig whose motor is slowed down (:mod:`nlgrd.timedomain.ramp_links`).

Method: the HHT-α recurrence of :class:`nlgrd.timedomain.links.LinkIntegrator` with a
fixed step Δt = 2π / (ω_0 steps_per_period) throughout (finer per cycle as the speed
falls). The link forcing enters along the link directions as the link forces do with the
opposite sign, the harmonic forces along their DOFs, so the linear part of a block of
fixed steps is the affine map of :class:`nlgrd.timedomain.period_map.PeriodMap` (built
for a block of steps instead of a period) and a step costs a dot product and the links'
own equation: Newton on the link coordinates
(:func:`~nlgrd.timedomain.links.newton_links`), or for a model whose only link and
excitation is one gear mesh the exact scalar contact solve (the same recurrence; the
two agree to 1e-12). The speed-dependent matrices (gyroscopic Ω G, circulatory,
tabulated bearings) are held at the speed at which the block map was built and rebuilt
whenever the speed has moved by ``speed_rtol``.

The ramp starts from the periodic steady state at ω_0 (integrated first at constant speed
from ``state0``, e.g. a harmonic-balance orbit from
:func:`nlgrd.timedomain.links.start_from_harmonics`), and each base cycle (θ from 2πk to
2π(k+1)) is summarised per link (:class:`RampResult`): a gear mesh's mean and RMS of the
alternating DTE, largest mesh force and contact-loss fraction; a bearing clearance's
contact fraction, largest force and radial displacement. Hysteretic damping has no time
form and is refused.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd
from numpy.typing import NDArray

from nlgrd.errors import ModelError
from nlgrd.nonlinear.links.contract import GearMeshLink
from nlgrd.nonlinear.models.link_model import LinkModel
from nlgrd.threads import single_blas_thread
from nlgrd.timedomain.links import backlash_force, link_time_response
from nlgrd.timedomain.ramp_links import block_map, multi_link_ramp
from nlgrd.units import column

#: Per link kind: the outputs of each cycle, in SI, and the one a jump is read on.
_LEVEL = {"gear mesh": "dte_rms [m]", "bearing clearance": "displacement_rms [m]"}


@dataclass(frozen=True)
class RampResult:
    """Base-cycle summaries of a time integration under a linear speed ramp, per link.

    A cycle is one period of the base frequency (θ from 2πk to 2π(k+1)): the mesh cycle of
    a model of one mesh or an idler train, a common divisor of the mesh frequencies of a
    multi-stage train, a shaft revolution of a rotor without gears
    (:class:`~nlgrd.nonlinear.links.frequency_plan.FrequencyPlan`).

    Attributes
    ----------
    omega : ndarray (n_cycles,)
        Base frequency at the middle of each cycle [rad/s].
    time : ndarray (n_cycles,)
        Time at the middle of each cycle, from the start of the ramp [s].
    outputs : dict of str -> dict of str -> ndarray (n_cycles,)
        Per link name its outputs of each cycle in SI, ``"<quantity> [unit]"``: a gear
        mesh ``dte_mean [m]`` and ``dte_rms [m]`` (mean and RMS of the alternating part of
        the DTE δ), ``elastic_force_max [N]`` (the largest mesh force k f(δ - e), without
        the damping force) and ``contact_loss_fraction [-]`` (steps without contact); a
        bearing clearance ``contact_fraction [-]`` (steps with r > c), ``force_max [N]``,
        ``displacement_max [m]`` and ``displacement_rms [m]`` (of the radial displacement
        r); another link ``force_max [N]`` and ``displacement_max [m]`` (norms over its
        coordinates).
    kinds : dict of str -> str
        Per link name its kind ("gear mesh", "bearing clearance", ...).
    rate : float
        Ramp rate of the base frequency, dω/dt = -rate [rad/s²].
    dt : float
        Time step [s].
    speed_per_base : float
        Reference shaft speed per base frequency, Ω/ω [-].
    link : str
        The default link of :meth:`jump`, :meth:`plot` and the ``dte_*`` properties: the
        first gear mesh (the first link without one).
    """

    omega: NDArray
    time: NDArray
    outputs: dict
    kinds: dict
    rate: float
    dt: float
    speed_per_base: float
    link: str = "mesh0"

    @property
    def rpm(self) -> NDArray:
        """Reference shaft speed of each cycle [rpm]."""
        return self.omega * self.speed_per_base * 30 / np.pi

    def _of(self, link: str | None) -> str:
        name = self.link if link is None else link
        if name not in self.outputs:
            raise ModelError("link", f"no link {name!r} in the ramp; its links are {list(self.outputs)}")
        return name

    def _mesh_output(self, quantity: str) -> NDArray:
        if self.kinds.get(self.link) != "gear mesh":
            raise ModelError("link", f"{self.link!r} is not a gear mesh: use outputs[{self.link!r}]")
        return self.outputs[self.link][quantity]

    @property
    def dte_mean(self) -> NDArray:
        """Mean DTE of each cycle of the default gear mesh [m]."""
        return self._mesh_output("dte_mean [m]")

    @property
    def dte_rms(self) -> NDArray:
        """RMS of the alternating DTE of each cycle of the default gear mesh [m]."""
        return self._mesh_output("dte_rms [m]")

    @property
    def force_max(self) -> NDArray:
        """Largest elastic mesh force of each cycle of the default gear mesh [N]."""
        return self._mesh_output("elastic_force_max [N]")

    @property
    def contact_loss_fraction(self) -> NDArray:
        """Fraction of each cycle without contact of the default gear mesh [-]."""
        return self._mesh_output("contact_loss_fraction [-]")

    def level(self, link: str | None = None) -> NDArray:
        """The output a jump is read on, per cycle: a gear mesh's DTE RMS, a bearing
        clearance's radial displacement RMS, another link's largest displacement [m].

        Parameters
        ----------
        link : str, optional
            The link's name; default :attr:`link`.

        Returns
        -------
        ndarray (n_cycles,)
        """
        name = self._of(link)
        return self.outputs[name][_LEVEL.get(self.kinds[name], "displacement_max [m]")]

    def smoothed_rms(self, n_cycles: int = 50, link: str | None = None) -> NDArray:
        """:meth:`level` over a moving window of ``n_cycles`` cycles (the root of the mean
        square), ending at each cycle [m]; the first cycles average what there is.

        Parameters
        ----------
        n_cycles : int
            Window length in cycles [-].
        link : str, optional
            The link; default :attr:`link`.

        Returns
        -------
        ndarray (n_cycles of the result,)
        """
        ms = np.concatenate([[0.0], np.cumsum(self.level(link) ** 2)])
        i = np.arange(1, ms.size)
        lo = np.maximum(i - int(n_cycles), 0)
        return np.sqrt((ms[i] - ms[lo]) / (i - lo))

    def jump(self, ratio: float = 0.5, n_cycles: int = 50, link: str | None = None) -> float | None:
        """Base frequency [rad/s] of the down jump of ``link``: the first cycle where its
        smoothed level (:meth:`smoothed_rms`) falls below ``ratio`` times the largest
        smoothed value before it (the definition of
        :func:`nlgrd.studies.experimental.resonance_jumps`, a fall to less than half);
        None when it never does.

        Parameters
        ----------
        ratio : float
            Fall that makes a jump [-].
        n_cycles : int
            Smoothing window in cycles [-].
        link : str, optional
            The link; default :attr:`link` (the first gear mesh).

        Returns
        -------
        float or None
        """
        s = self.smoothed_rms(n_cycles, link)
        hit = np.nonzero(s < ratio * np.maximum.accumulate(s))[0]
        return float(self.omega[hit[0]]) if hit.size else None

    def to_frame(self) -> pd.DataFrame:
        """One row per cycle, units in the column names (docs/conventions.md, "Column
        names": every link's outputs ``<link>.<quantity> [unit]``, lengths in µm)."""
        cols = {
            "time [s]": self.time,
            "shaft_speed [rpm]": self.rpm,
            "base_frequency [Hz]": self.omega / (2 * np.pi),
        }
        for name, outs in self.outputs.items():
            for key, v in outs.items():
                quantity, unit = key[:-1].split(" [")
                cols[column(quantity, "um" if unit == "m" else unit, name)] = v * 1e6 if unit == "m" else v
        return pd.DataFrame(cols)

    def plot(self, ax=None, label: str | None = None, link: str | None = None):
        """:meth:`level` per cycle against the reference shaft speed, the jump marked
        (:func:`nlgrd.plotting.nonlinear.plot_ramp`).

        Parameters
        ----------
        ax : matplotlib.axes.Axes, optional
            Axes to draw on; a new figure when None.
        label : str, optional
            Legend label of the curve.
        link : str, optional
            The link; default :attr:`link` (the first gear mesh).

        Returns
        -------
        matplotlib.axes.Axes
        """
        from nlgrd.plotting.nonlinear import plot_ramp

        name = self._of(link)
        j = self.jump(link=name)
        rpm_jump = None if j is None else j * self.speed_per_base * 30 / np.pi
        kind = self.kinds[name]
        ylabel = None if kind == "gear mesh" else f"{name}: " + _LEVEL.get(kind, "displacement_max [m]")
        ylabel = ylabel and ylabel.replace("[m]", "[µm]").replace("_", " ")
        return plot_ramp(self.rpm, self.level(name) * 1e6, rpm_jump, ax=ax, label=label, ylabel=ylabel)


class _CycleStats:
    """Running per-cycle sums and maxima of every link's outputs (:class:`RampResult`)."""

    def __init__(self, links, slices, n: int, w0: float, rate: float):
        self.links, self.slices, self.w0, self.rate = tuple(links), tuple(slices), w0, rate
        sizes = [3 if isinstance(lk, GearMeshLink) else 2 * (lk.kind == "bearing clearance") for lk in links]
        self.sums = [np.zeros((3, n))] + [np.zeros((k, n)) for k in sizes]  # count, Σt, Σω; per link
        self.maxes = [np.full((2, n), -np.inf) for _ in self.links]

    def _values(self, link, y: NDArray, g: NDArray) -> tuple[list, list]:
        """The summed and the maximised per-step values of one link ((d, n) arrays in)."""
        if isinstance(link, GearMeshLink):
            return [y[0], y[0] ** 2, g[0] == 0.0], [g[0], g[0]]
        if link.kind == "bearing clearance":
            r = np.hypot(y[0], y[1])
            return [r * r, r > link.clearance], [np.hypot(g[0], g[1]), r]
        return [], [np.linalg.norm(g, axis=0), np.linalg.norm(y, axis=0)]

    def add(self, t: NDArray, y: NDArray, g: NDArray) -> None:
        """One block: times at the steps' starts (n,) [s], link coordinates and forces (d, n)."""
        th = self.w0 * t - 0.5 * self.rate * t**2
        # cycle k: θ in [2πk, 2π(k+1)); 1e-9 cycles of slack keep a step that lands on a
        # cycle's start there despite the rounding of θ
        cycle = np.floor(th / (2 * np.pi) + 1e-9).astype(int)
        c0 = int(cycle[0])
        idx = cycle - c0
        m = int(idx[-1]) + 1
        rows = [[np.ones_like(t), t, self.w0 - self.rate * t]]
        peaks = []
        for link, sl in zip(self.links, self.slices, strict=True):
            summed, peak = self._values(link, y[sl], g[sl])
            rows.append(summed)
            peaks.append(peak)
        for i, vals in enumerate(rows):
            for row, v in enumerate(vals):
                self.sums[i][row, c0 : c0 + m] += np.bincount(idx, weights=v, minlength=m)
        for i, vals in enumerate(peaks):
            for row, v in enumerate(vals):
                np.maximum.at(self.maxes[i][row], cycle, v)

    def outputs(self) -> tuple[NDArray, NDArray, dict]:
        """(ω, t, per link outputs) of the whole cycles (not the last, cut, one)."""
        n, st, so = self.sums[0]
        idx = np.nonzero(n > 0)[0][:-1]
        n = n[idx]
        out = {}
        for link, sums, peaks in zip(self.links, self.sums[1:], self.maxes, strict=True):
            s, mx = sums[:, idx] / n, peaks[:, idx]
            if isinstance(link, GearMeshLink):
                mean = s[0]
                out[link.name] = {
                    "dte_mean [m]": mean,
                    "dte_rms [m]": np.sqrt(np.maximum(s[1] - mean**2, 0.0)),
                    "elastic_force_max [N]": mx[0],
                    "contact_loss_fraction [-]": s[2],
                }
            elif link.kind == "bearing clearance":
                out[link.name] = {
                    "contact_fraction [-]": s[1],
                    "force_max [N]": mx[0],
                    "displacement_max [m]": mx[1],
                    "displacement_rms [m]": np.sqrt(s[0]),
                }
            else:
                out[link.name] = {"force_max [N]": mx[0], "displacement_max [m]": mx[1]}
        return so[idx] / n, st[idx] / n, out


def _check_model(model: LinkModel) -> None:
    """Refuse, in one line, what has no time-domain form: hysteretic damping."""
    if model.receptance.model.hysteretic_parts:
        raise ModelError(
            "loss_factor", "hysteretic shaft damping has no time-domain form; use viscous damping"
        )


def _one_mesh(model: LinkModel) -> GearMeshLink | None:
    """The gear mesh of a model whose only link it is and only excitation besides static
    loads: the closed-form fast path of the ramp; None otherwise."""
    links = tuple(model.links)
    if len(links) == 1 and isinstance(links[0], GearMeshLink) and model.receptance.harmonic_force is None:
        return links[0]
    return None


@single_blas_thread
def run_down(
    model: LinkModel,
    omega_start: float,
    omega_stop: float,
    rate: float,
    *,
    state0: tuple | None = None,
    steps_per_period: int = 128,
    alpha: float = -0.05,
    tol: float = 1e-6,
    block: int = 256,
    speed_rtol: float = 0.005,
) -> RampResult:
    """Integrate the full FE model while the base frequency falls linearly in time.

    Parameters
    ----------
    model : LinkModel
        The model (:func:`nlgrd.analyses.model`): any links (gear meshes, bearing
        clearances), static loads and unbalance; no hysteretic damping.
    omega_start, omega_stop : float
        Base frequency at the start and the end of the ramp [rad/s], ``omega_stop`` <
        ``omega_start`` (a run-down).
    rate : float
        The fall of the base frequency per second, -dω/dt > 0 [rad/s²] (reference shaft
        rpm/s = rate Ω/ω 30/π).
    state0 : tuple (q, q', q''), optional
        Start at θ = 0 of the settling run at ``omega_start`` (default the static solution).
    steps_per_period : int
        Time steps per base period at ``omega_start``; the step is kept fixed [-].
    alpha : float
        HHT-α parameter in [-1/3, 0] [-].
    tol : float
        Steady-state tolerance of the settling run at ``omega_start``
        (:func:`nlgrd.timedomain.links.link_time_response`) [-].
    block : int
        Steps per block map [-].
    speed_rtol : float
        Relative change of speed after which the speed-dependent matrices are rebuilt [-].

    Returns
    -------
    RampResult
        One summary per base cycle of the ramp, per link.

    Raises
    ------
    ModelError
        ``rate`` not positive or ``omega_stop`` not below ``omega_start``; a model with
        hysteretic damping (:func:`ramp_from`).
    """
    if not rate > 0:
        raise ModelError("rate", f"a run-down needs a positive rate, got {rate}")
    if not 0 < omega_stop < omega_start:
        raise ModelError("omega_stop", f"must lie in (0, omega_start = {omega_start}), got {omega_stop}")
    _check_model(model)
    settled = link_time_response(
        model, omega_start, steps_per_period=steps_per_period, tol=tol, state0=state0, max_periods=4000
    )
    duration = (omega_start - omega_stop) / rate
    return ramp_from(
        model, settled.state, omega_start, rate, duration, steps_per_period, alpha, block, speed_rtol
    )


@single_blas_thread
def ramp_from(
    model: LinkModel,
    state: tuple,
    omega_start: float,
    rate: float,
    duration: float,
    steps_per_period: int = 128,
    alpha: float = -0.05,
    block: int = 256,
    speed_rtol: float = 0.005,
    *,
    link_solve: str = "auto",
) -> RampResult:
    """The ramp of :func:`run_down` from a given state at θ = 0, without settling first;
    ``rate`` 0 integrates at constant speed (the check against the steady-state integrator).

    Parameters
    ----------
    model : LinkModel
        The model: any links and loads (:func:`run_down`).
    state : tuple (q, q', q'')
        State at θ = 0 [m, m/s, m/s²].
    omega_start : float
        Base frequency at the start [rad/s].
    rate : float
        -dω/dt >= 0 [rad/s²].
    duration : float
        Time integrated [s] (whole blocks: up to ``block`` steps more).
    steps_per_period, alpha, block, speed_rtol : int, float, int, float
        As :func:`run_down`.
    link_solve : {"auto", "newton"}
        "auto": the closed-form scalar step when the model's only link and excitation is
        one gear mesh, Newton on the link coordinates otherwise; "newton": Newton always
        (:func:`~nlgrd.timedomain.links.newton_links`).

    Returns
    -------
    RampResult

    Raises
    ------
    ModelError
        A negative ``rate``, a ramp that reaches zero speed, a ``link_solve`` not known,
        hysteretic damping.
    """
    _check_model(model)
    if link_solve not in ("auto", "newton"):
        raise ModelError("link_solve", f"'auto' or 'newton', got {link_solve!r}")
    w0 = float(omega_start)
    dt = 2 * np.pi / (w0 * steps_per_period)
    if rate < 0 or rate * duration >= w0:
        raise ModelError(
            "rate", f"the ramp must stay at positive speeds and fall: rate {rate}, duration {duration}"
        )
    n_blocks = -(-int(np.ceil(duration / dt)) // block)
    theta_end = w0 * n_blocks * block * dt
    rec = model.receptance
    links = tuple(model.links)
    stats = _CycleStats(links, rec.slices, int(theta_end / (2 * np.pi)) + 2, w0, float(rate))
    mesh = _one_mesh(model)
    if mesh is not None and link_solve == "auto":
        _one_mesh_ramp(model, mesh, state, w0, rate, dt, n_blocks, alpha, block, speed_rtol, stats.add)
    else:
        multi_link_ramp(model, state, w0, rate, dt, n_blocks, alpha, block, speed_rtol, stats.add)
    omega, time, outputs = stats.outputs()
    first = next((lk.name for lk in links if isinstance(lk, GearMeshLink)), links[0].name)
    return RampResult(
        omega=omega,
        time=time,
        outputs=outputs,
        kinds={lk.name: lk.kind for lk in links},
        rate=float(rate),
        dt=dt,
        speed_per_base=rec.plan.speed_per_base,
        link=first,
    )


def _one_mesh_ramp(model, link, state, w0, rate, dt, n_blocks, alpha, block, speed_rtol, record) -> None:
    """The ramp of a model whose only link is one gear mesh, without other excitation: the
    step of :func:`~nlgrd.timedomain.ramp_links.multi_link_ramp` with the link solve in
    closed form (:func:`~nlgrd.timedomain.links.backlash_force`) and the LSTE forcing
    c_m e' folded into the one scalar input along w, G = g(δ - e) - c_m e' (the same
    recurrence: tests/test_run_down_links.py compares the two to 1e-12)."""
    rec = model.receptance
    lm = rec.model
    mesh = link.mesh
    w = np.asarray(rec.P[:, 0], dtype=float)
    F0 = np.asarray(rec.static_force, dtype=float).reshape(-1)
    b, c_m = mesh.half_backlash, mesh.damping
    z = np.asarray(mesh.lste, dtype=float)
    kk = np.arange(1, (z.size - 1) // 2 + 1)

    speed_of = rec.plan.speed
    speed_built = speed_of(w0)
    step, pmap = block_map(lm, rec.C_link, w[:, None], F0, speed_built, dt, alpha, block)
    u = np.asarray(state[0], dtype=float)

    def forcing(t):
        """θ, ω, e, k and the along-w forcing c_m e' at times t."""
        om = w0 - rate * t
        th = w0 * t - 0.5 * rate * t * t
        kt = np.multiply.outer(th, kk)
        c, s_ = np.cos(kt), np.sin(kt)
        e = z[0] + c @ z[1::2] + s_ @ z[2::2]
        de = c @ (kk * z[2::2]) - s_ @ (kk * z[1::2])  # de/dθ
        return th, om, e, mesh.stiffness_time(th), c_m * om * de

    th0, _, e0, k0, f0 = forcing(np.zeros(1))
    x0 = float(w @ u) - e0[0]
    g0 = k0[0] * (x0 - b) if x0 > b else (k0[0] * (x0 + b) if x0 < -b else 0.0)
    s = np.concatenate([u, state[1], state[2], [g0 - f0[0]]])
    g_buf = np.empty(block)
    for nb in range(n_blocks):
        t_next = dt * (nb * block + 1 + np.arange(block))  # the ends of the block's steps
        om_mid = w0 - rate * dt * (nb + 0.5) * block
        if abs(speed_of(om_mid) - speed_built) > speed_rtol * speed_built:
            speed_built = speed_of(om_mid)
            step, pmap = block_map(lm, rec.C_link, w[:, None], F0, speed_built, dt, alpha, block)
        apcw = step.ap * float(pmap.S[0, 0])
        _, _, e_n, k_n, f_n = forcing(t_next)
        e_l, k_l, f_l = e_n.tolist(), k_n.tolist(), f_n.tolist()

        def solve_link(y_lin: float, j: int, apcw=apcw, e_l=e_l, k_l=k_l, f_l=f_l) -> tuple[float, float]:
            pv = y_lin + apcw * f_l[j] - e_l[j]  # δ - e with no mesh force
            g = backlash_force(pv, k_l[j], b, apcw)
            g_buf[j] = g
            return pv + e_l[j] - apcw * g, g - f_l[j]

        ys, s = pmap.run(s, solve_link)
        g_start = np.concatenate([[g0], g_buf[:-1]])  # the mesh force at the steps' starts
        g0 = float(g_buf[-1])
        record(t_next - dt, ys[:1], g_start[None, :])

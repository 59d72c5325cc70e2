"""One way through a sweep for every model, behind one interface (a *view*), so that ``nlgrd
sweep`` and the orbit search run one flow: :class:`LinkView`, any set of meshes, clearances
and unbalance (:func:`~nlgrd.nonlinear.models.link_model.build_link_model`, one mesh too):
``link_sweep``, ``link_continuation``; its table and orbits have the base frequency, the
reference shaft speed and every link's and linear bearing's outputs over the orbit's whole
period.

The orbit search on it: :func:`search_beside` (``--search-at``: ``<out>_orbits.csv``,
every orbit found with whether the sweep has it, and ``<out>_branches.csv``, the branch of
each stable orbit the sweep does not have, followed over the grid) and
:func:`period_branches` (``--period N``: the same two and the merged period-N response), both
over :mod:`nlgrd.nonlinear.tracing.period_branches`.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from nlgrd.nonlinear.tracing.period_branches import PERIOD_HARMONICS


def _unit(name: str) -> str:
    """The unit of an output column ``<name> [unit]`` ("" without one)."""
    return name.rsplit("[", 1)[1] if name.endswith("]") and "[" in name else ""


def same_outputs(sweep: dict, orbit: dict, rtol: float = 1e-6) -> bool:
    """Whether an orbit's outputs are the sweep point's: every column of ``orbit`` to
    ``rtol`` of itself or of the largest of the sweep point's columns in its unit.

    The absolute part is the problem's scale: a bearing the mesh does not load gets
    rounding of the recovery (1e-66 to 1e-8 N beside 1e3 N on Kubo's rig, different on
    every BLAS kernel), which no relative comparison of its own can pass.

    Parameters
    ----------
    sweep : dict
        The sweep point's outputs, ``<name> [unit]`` -> value.
    orbit : dict
        The orbit's outputs, keys among ``sweep``'s.
    rtol : float
        Relative tolerance [-].

    Returns
    -------
    bool
    """
    scale: dict[str, float] = {}
    for k, v in sweep.items():
        number = isinstance(v, (float, int, np.floating, np.integer)) and not isinstance(v, bool)
        if number and np.isfinite(v):
            scale[_unit(k)] = max(scale.get(_unit(k), 0.0), abs(float(v)))
    atol = {k: rtol * scale.get(_unit(k), 0.0) for k in orbit}
    return all(bool(np.isclose(sweep[k], v, rtol=rtol, atol=atol[k])) for k, v in orbit.items())


class LinkView:
    """A link model: its sweep and continuation, the sweep's table and figure, the period-ν
    models and what is written of each orbit and branch: the base frequency, the reference
    shaft speed and every link's outputs over the orbit's whole period (as
    :func:`~nlgrd.nonlinear.models.link_model.link_sweep`'s columns).

    Parameters
    ----------
    model : LinkModel
        The sweep's model.
    column : str or None
        The output column drawn, continued and printed for each orbit (``--quantity``;
        None: the periodic models alone, as :func:`nlgrd.analyses.search_orbits` uses).
    """

    def __init__(self, model, column: str | None):
        from nlgrd.nonlinear.results.link_results import output_names

        self.model, self.column = model, column
        self.per_base = model.receptance.plan.speed_per_base * 60  # [rpm per Hz of the base]
        self.outputs = output_names(model)
        self.columns = (
            "search at",
            "base_frequency [Hz]",
            "shaft_speed [rpm]",
            "period",
            "stable",
            "floquet_max [-]",
            "on the sweep",
            *self.outputs,
            "amplitude [um]",
            "start",
        )

    def points(self, res):
        """The harmonic-balance points of a sweep of this model (a SweepResult)."""
        return res.result

    def sweep(self, omegas, H, directions: str, stability: bool, period, progress=None):
        """:func:`~nlgrd.nonlinear.models.link_model.link_sweep` of the model over ``omegas`` [rad/s]."""
        from nlgrd.nonlinear.models.link_model import link_sweep

        return link_sweep(
            self.model,
            omegas,
            H=H,
            directions=directions,
            stability=stability,
            period=period,
            progress=progress,
        )

    def continuation(self, begin: float, end: float, H, quantity: str, stability: bool, **options):
        """:func:`~nlgrd.nonlinear.models.link_model.link_continuation` from ``begin`` to
        ``end`` [rad/s]: the curve (its metrics hold the output column ``quantity`` as the
        table writes it, :func:`nlgrd.units.written_name`) and its table."""
        import dataclasses

        from nlgrd.nonlinear.models.link_model import link_continuation
        from nlgrd.units import written_frame

        res = link_continuation(self.model, begin, end, H, stability=stability, **options)
        table = written_frame(res.links[[quantity]])  # the column as the CSV writes it
        name = str(table.columns[0])
        metrics = {**res.curve.curve.metrics, name: table[name].to_numpy()}
        curve = dataclasses.replace(res.curve, curve=dataclasses.replace(res.curve.curve, metrics=metrics))
        return curve, res.to_frame()

    def time_model(self):
        """The model :func:`nlgrd.timedomain.sweep_answers.answer_sweep` takes: this one."""
        return self.model

    def period(self, nu: int):
        """The period-ν model (:func:`~nlgrd.nonlinear.models.link_model.period_model`)."""
        from nlgrd.nonlinear.models.link_model import period_model

        return period_model(self.model, nu)

    def values(self, harmonics, omega: float, nu: int) -> dict:
        """Every link's and bearing's outputs of an orbit of ν base periods at the base
        frequency ω [rad/s]."""
        from nlgrd.nonlinear.results.link_results import point_outputs

        return point_outputs(self.period(nu), harmonics, omega / nu)

    def row(self, o) -> dict:
        hz = o.omega / (2 * np.pi)
        return {
            "base_frequency [Hz]": hz,
            "shaft_speed [rpm]": hz * self.per_base,
            **self.values(o.harmonics, o.omega, o.period),
        }

    def text(self, row: dict) -> str:
        from nlgrd.units import written_frame

        one = written_frame(pd.DataFrame({self.column: [row[self.column]]}))  # as the CSV writes it
        return f"{one.columns[0]} {one.iloc[0, 0]:.4g}"

    def table(self, res) -> pd.DataFrame:
        """The sweep's table (:meth:`LinkSweepResult.to_frame`) with the reference shaft
        speed beside the base frequency."""
        frame = res.to_frame()
        per_base = self.model.receptance.plan.speed_per_base
        frame.insert(1, "shaft_speed [rpm]", frame["base_frequency [Hz]"] * per_base * 60)
        return frame

    def words(self) -> str:
        """What the sweep's summary says of the model before its H: its links and base."""
        plan = self.model.receptance.plan
        return (
            f"links {', '.join(lk.name for lk in self.model.links)}, base frequency = {plan.name} "
            f"({1 / plan.speed_per_base:.6g} x the shaft speed), "
        )

    def figure(self, res, frame, quantity: str, x: str, xaxis, title: str, branches=None):
        """The sweep's figure: the column ``quantity`` of ``frame`` against its column ``x``,
        the branches when given (:func:`nlgrd.plotting.sweep_figures.plot_link_sweep`)."""
        from nlgrd.plotting.sweep_figures import plot_link_sweep
        from nlgrd.units import written_name

        title = f"{title}\nbase frequency: {self.model.receptance.plan.name}, H = {res.result.H}"
        return plot_link_sweep(frame, x, written_name(quantity), title, branches).figure

    def on_sweep(self, res):
        """``known(orbit, omega, followed)``: the sweep ``res`` has the orbit (its period and
        every output, :func:`same_outputs`) at a converged, stable point of that speed."""
        r = res.result

        def known(o, w: float, followed) -> bool:
            here = np.nonzero(
                np.isclose(r.omega, w, rtol=1e-12) & r.converged & ~np.asarray(r.no_stable, dtype=bool)
            )[0]
            mine = self.values(o.harmonics, o.omega, o.period)
            return any(
                int(r.period[i]) == o.period and same_outputs(res.links.iloc[i][self.outputs].to_dict(), mine)
                for i in here
            )

        return known

    def result(self, branch, H: int | None = None):
        """``branch`` (one period) with every link's outputs where it is the response: a
        :class:`~nlgrd.nonlinear.results.link_results.LinkSweepResult`."""
        from nlgrd.nonlinear.results.link_results import LinkSweepResult, bearing_columns

        nu = int(branch.period[0]) if len(branch) else 1
        usable = branch.converged & ~np.asarray(branch.no_stable, dtype=bool)
        blank = dict.fromkeys(self.outputs, np.nan)
        rows = [
            self.values(branch.harmonics[i], float(branch.omega[i]), nu) if usable[i] else blank
            for i in range(len(branch))
        ]
        return LinkSweepResult(branch, pd.DataFrame(rows, columns=self.outputs), bearing_columns(self.model))

    def frame(self, branch) -> pd.DataFrame:
        f = self.result(branch).to_frame()
        f.insert(0, "shaft_speed [rpm]", f["base_frequency [Hz]"] * self.per_base)
        return f

    def model_of(self, H: int, top: float):
        """``model_of(nu)`` for the orbit search: the period-ν reduced model, its basis
        serving H harmonics of the base up to ``top`` [rad/s]."""

        def model_of(nu: int):
            m = self.period(nu)
            m.receptance.prepare(H * top)  # a modal basis (large models) serving νH harmonics of ω/ν
            return m.reduced

        return model_of


def search_beside(view, res, omegas, at, periods, unit, report=None) -> tuple[pd.DataFrame, pd.DataFrame]:
    """``--search-at``: search at each speed, report what was found, follow the stable orbits
    the sweep does not have over its grid
    (:func:`~nlgrd.nonlinear.tracing.period_branches.search_and_follow`).

    Parameters
    ----------
    view : LinkView
        The sweep's model and its columns.
    res : LinkSweepResult
        The sweep.
    omegas : ndarray
        The sweep's base frequencies [rad/s].
    at : ndarray
        Search speeds, in the unit of ``unit``.
    periods : tuple of int
        Periods sought [base periods].
    unit : callable
        Base frequency [rad/s] to text in the range's unit; ``unit.omega`` the inverse.
    report : callable, optional
        Takes each progress line (None: silent).

    Returns
    -------
    (DataFrame, DataFrame)
        The orbits found and the followed branches.
    """
    from nlgrd.nonlinear.tracing.period_branches import search_and_follow

    H = view.points(res).H
    model_of = view.model_of(H, float(np.max(omegas)))
    orbits, branches, _ = search_and_follow(
        model_of, omegas, at, periods, H, unit, view.on_sweep(res), "the sweep's", view, report=report
    )
    if orbits.empty and report is not None:
        report("orbit search: nothing converged at the speeds given")
    return orbits, branches


def period_branches(view, omegas, at, nu: int, H: int | None, directions: str, unit, report=None):
    """``--period N`` (N >= 3): period-N orbits searched at ``at``, each new one followed over
    the grid, the branches merged into one response per grid point and direction, its
    harmonic error estimated at the next rung
    (:func:`~nlgrd.nonlinear.tracing.period_branches.period_response`).

    Parameters
    ----------
    view : LinkView
        The model and its columns.
    omegas : ndarray
        The grid's base frequencies [rad/s].
    at : ndarray
        Search speeds, in the unit of ``unit``.
    nu : int
        The period sought [base periods].
    H : int or None
        Harmonics of the base (ν H of ω/ν); None: :data:`PERIOD_HARMONICS`.
    directions : {"both", "up", "down"}
        Sweep directions of the response.
    unit : callable
        Base frequency [rad/s] to text in the range's unit; ``unit.omega`` the inverse.
    report : callable, optional
        Takes each progress line (None: silent).

    Returns
    -------
    (LinkSweepResult or None, DataFrame, DataFrame)
        The response (None when no period-ν orbit was found), the orbits found and the
        followed branches.
    """
    from nlgrd.nonlinear.tracing.orbit_search import N_STARTS
    from nlgrd.nonlinear.tracing.period_branches import period_response

    H = H or PERIOD_HARMONICS
    top = float(np.max(omegas))
    if report is not None:
        where = ", ".join(f"{v:g}" for v in at) + f" {unit.name}"
        report(f"period {nu}: searching at {where} ({N_STARTS} starts each, H = {H})")
    res, orbits, frames = period_response(
        view.model_of(H, top),
        lambda H_check: view.model_of(H_check, top)(nu),
        omegas,
        at,
        nu,
        H,
        unit,
        directions,
        view,
        report=report,
    )
    return (None if res is None else view.result(res, H)), orbits, frames

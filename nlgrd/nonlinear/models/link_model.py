"""A rotor model with any number of nonlinear links: build, sweep, per-link outputs.

:func:`build_link_model` reduces a :class:`~nlgrd.rotor.system.RotorSystem` onto the
coordinates of its links (:mod:`nlgrd.nonlinear.reduction.link_reduction`) with unbalance and
gravity as loads; :func:`link_sweep` runs the harmonic-balance sweep of
:func:`nlgrd.nonlinear.tracing.sweep.sweep` on it, with Floquet stability, and writes every
link's outputs in columns named ``<link>.<quantity>``. Where a period-1 orbit loses
stability by period doubling it follows the period-2 orbits on :func:`period_model`, the
same links on the base ω/2 (:mod:`nlgrd.nonlinear.tracing.auto_period`).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np
import pandas as pd
from numpy.typing import NDArray

from nlgrd.cache import BoundedCache
from nlgrd.errors import ModelError
from nlgrd.nonlinear.hb.harmonic_balance import ReducedModel
from nlgrd.nonlinear.links.contract import GearMeshLink
from nlgrd.nonlinear.links.frequency_plan import FrequencyPlan
from nlgrd.nonlinear.reduction.link_reduction import LinkReceptance
from nlgrd.nonlinear.reduction.state_space import HYSTERETIC_REFUSAL
from nlgrd.nonlinear.results.link_results import (  # re-exported: the tables live there
    LinkContinuationResult,
    LinkSweepResult,
    bearing_columns,
    link_rows,
    metric_names,
    output_names,
    points_outputs,
    with_amplitudes,
)
from nlgrd.nonlinear.results.metrics import PointMetrics
from nlgrd.nonlinear.tracing.auto_period import beyond_period_one, check_period
from nlgrd.nonlinear.tracing.continuation import continuation
from nlgrd.nonlinear.tracing.harmonic_convergence import (
    LADDER,
    OUTPUT_RTOL,
    converged_continuation,
    converged_sweep,
    next_harmonics,
)
from nlgrd.nonlinear.tracing.sweep import sweep
from nlgrd.rotor.assembly import assemble
from nlgrd.rotor.loads import Unbalance  # re-exported: moved to nlgrd.rotor (the model file holds it)
from nlgrd.rotor.system import RotorSystem

_UY, _UZ = 1, 2


@dataclass(frozen=True)
class LinkModel:
    """A reduced rotor model with nonlinear links.

    Attributes
    ----------
    system : RotorSystem
        The rotor.
    links : tuple of NonlinearLink
        The links, in the order of their coordinates.
    receptance : LinkReceptance
        The reduction.
    reduced : ReducedModel
        The harmonic-balance model on the link coordinates (base frequency ω [rad/s]).
    top_order : int
        The highest base harmonic an excitation sits at (a mesh's order, an unbalance's).
    period : int
        Base periods of the plan it was built on per period of its base: 1, or ν for the
        model of :func:`period_model`, whose base is ω/ν [-].
    loads : dict
        The unbalance, gravity and reduction options it was built with (to build
        :func:`period_model`).
    """

    system: RotorSystem
    links: tuple
    receptance: LinkReceptance
    reduced: ReducedModel
    top_order: int = 1
    period: int = 1
    loads: dict = field(default_factory=dict, repr=False, compare=False)

    @cached_property
    def cache(self) -> BoundedCache:
        """Models derived from this one (:func:`period_model`)."""
        return BoundedCache(4)

    @cached_property
    def output_cache(self) -> BoundedCache:
        """Tables the per-point outputs reuse (the period's samples of the bearing maxima, per H)."""
        return BoundedCache(8)

    def link_harmonics(self, harmonics: NDArray, name: str) -> NDArray:
        """The rows of the link ``name`` in the harmonics (d_total, 2H+1) of a point [m].

        Parameters
        ----------
        harmonics : ndarray (d_total, 2H+1)
            Real harmonics of all link coordinates [m].
        name : str
            A link's name.

        Returns
        -------
        ndarray (d, 2H+1)
        """
        for link, sl in zip(self.links, self.receptance.slices, strict=True):
            if link.name == name:
                return np.asarray(harmonics)[sl]
        raise ModelError("link", f"no link {name!r} (links: {', '.join(lk.name for lk in self.links)})")


def _gravity_force(system: RotorSystem, M, gravity) -> NDArray:
    a = np.zeros(system.n_dofs)
    gy, gz = gravity
    for s, shaft in enumerate(system.shafts):
        for n in range(shaft.n_nodes):
            d = system.dofs.node_dofs(s, n)
            a[d[_UY]], a[d[_UZ]] = gy, gz
    return M @ a


def gear_links(system: RotorSystem, plan: FrequencyPlan) -> list[GearMeshLink]:
    """The links of all gear pairs of ``system``, named ``mesh<i>``, each at its base harmonic.

    Parameters
    ----------
    system : RotorSystem
        The model.
    plan : FrequencyPlan
        The base frequency.

    Returns
    -------
    list of GearMeshLink
    """
    out = []
    for i, g in enumerate(system.gear_pairs):
        s_p = system.shafts[g.pinion_shaft].speed_ratio
        m = plan.order(g.geometry.teeth_pinion * s_p, f"the mesh of gear_pairs[{i}]")
        out.append(GearMeshLink.from_system(system, i, order=m))
    return out


def build_link_model(
    system: RotorSystem,
    links: Sequence = (),
    *,
    plan: FrequencyPlan | None = None,
    unbalance: Sequence[Unbalance] | None = None,
    gravity: tuple[float, float] | None = None,
    method: str = "auto",
    max_frequency: float | None = None,
) -> LinkModel:
    """Reduce ``system`` onto its links' coordinates, with unbalance and gravity loads.

    Every gear pair of ``system`` is a link: those not among ``links`` (a
    :class:`GearMeshLink` with its ``index``) are added by :func:`gear_links`, after
    ``links`` and the system's ``bearing_clearances``. The gear pairs' static torques
    are loads of the mean problem.

    Parameters
    ----------
    system : RotorSystem
        The rotor (bearings, disks, couplings: linear).
    links : sequence of NonlinearLink
        The links (names unique).
    plan : FrequencyPlan, optional
        Base frequency and speed; default :meth:`FrequencyPlan.for_system` (the mesh
        frequency for one mesh, the shaft speed for a rotor without gears).
    unbalance : sequence of Unbalance, optional
        Unbalances, each at harmonic |s| Ω of its shaft (s its speed ratio); default the
        system's own ``unbalance`` (a model file's ``[[unbalance]]``), ``()`` for none.
    gravity : tuple of float, optional
        Acceleration of gravity (g_y, g_z) on every node [m/s^2], e.g. (-9.81, 0).
    method : {"auto", "poles", "direct", "modal"}
        How the reduction solves Z_k (:class:`LinkReceptance`).
    max_frequency : float, optional
        Highest excitation frequency for a modal basis [rad/s]; by default
        :func:`link_sweep` sets it from its frequencies and H.

    Returns
    -------
    LinkModel

    Raises
    ------
    ModelError
        A model without any link (no gear pair, no clearance): a linear rotor, nothing
        nonlinear to solve (``nlgrd modes``, ``campbell`` give its response).
    """
    unbalance = system.unbalance if unbalance is None else tuple(unbalance)
    unb_orders = [abs(system.shafts[u.shaft].speed_ratio) for u in unbalance]
    plan = plan or FrequencyPlan.for_system(system, unb_orders)
    links = model_links(system, links, plan)
    if not links:  # a linear rotor: its response is modal analysis and frequency response
        raise ModelError("gear_pairs", "the model has no gear pair and no clearance: no link to reduce onto")
    loads = dict(unbalance=unbalance, gravity=gravity, method=method, max_frequency=max_frequency)
    return _reduce(system, links, plan, loads)


def model_links(system: RotorSystem, links: Sequence = (), plan: FrequencyPlan | None = None) -> tuple:
    """The links :func:`build_link_model` reduces ``system`` onto, without reducing: ``links``,
    the system's bearing clearances, then every gear pair not among ``links``
    (:func:`gear_links`). What the command line checks ``--quantity`` against before any
    computation.

    Parameters
    ----------
    system : RotorSystem
        The model.
    links : sequence of NonlinearLink
        Links given.
    plan : FrequencyPlan, optional
        Default :meth:`FrequencyPlan.for_system` with the system's unbalance.

    Returns
    -------
    tuple of NonlinearLink
    """
    if plan is None:
        plan = FrequencyPlan.for_system(
            system, [abs(system.shafts[u.shaft].speed_ratio) for u in system.unbalance]
        )
    links = list(links) + list(system.bearing_clearances)
    given = {lk.index for lk in links if isinstance(lk, GearMeshLink) and lk.index is not None}
    return tuple(links + [lk for lk in gear_links(system, plan) if lk.index not in given])


def period_model(model: LinkModel, nu: int = 2) -> LinkModel:
    """The model of orbits of ``nu`` base periods: the same links and loads on the base ω/ν.

    Every excitation moves from base harmonic k to νk (a mesh at m to ν m, its LSTE
    harmonic j at ν m j; an unbalance likewise; :meth:`FrequencyPlan.subharmonic`), the
    response holds all harmonics of ω/ν; the components at harmonics that are not
    multiples of ν are the subharmonic content (:mod:`nlgrd.nonlinear.tracing.subharmonic`). A
    link moves by its ``subharmonic(nu)`` (a link without one does not depend on the base).
    Kept in ``model.cache``.

    Parameters
    ----------
    model : LinkModel
        From :func:`build_link_model`.
    nu : int
        Base periods of the new base [-], >= 1.

    Returns
    -------
    LinkModel
        Solved at ω/ν for a base frequency ω of ``model`` (its ``period`` ν).

    Raises
    ------
    ModelError
        ν not an integer >= 1, or ``model`` without the loads it was built with.
    """
    plan = model.receptance.plan.subharmonic(nu)  # checks nu
    if int(nu) == 1:
        return model

    def make() -> LinkModel:
        links = tuple(lk.subharmonic(int(nu)) if hasattr(lk, "subharmonic") else lk for lk in model.links)
        if not model.loads:
            raise ModelError("model", "a period-ν model needs the loads of its model (build_link_model)")
        return _reduce(model.system, links, plan, model.loads, model.period * int(nu))

    return model.cache.get(("period", int(nu)), make)


def _reduce(system: RotorSystem, links: tuple, plan: FrequencyPlan, loads: dict, period: int = 1):
    """The LinkModel of ``links`` (all of them) on ``plan`` with the ``loads`` of
    :func:`build_link_model`."""
    unbalance, gravity = loads["unbalance"], loads["gravity"]
    unb_orders = [abs(system.shafts[u.shaft].speed_ratio) for u in unbalance]
    names = [lk.name for lk in links]
    if len(set(names)) != len(names):
        raise ModelError("links", f"link names must be unique, got {names}")
    n = system.n_dofs
    unb = []
    for u, s in zip(unbalance, unb_orders, strict=True):
        ratio = system.shafts[u.shaft].speed_ratio
        m = plan.order(s, f"the unbalance on shaft {u.shaft}")
        d = system.dofs.node_dofs(u.shaft, u.node)
        unb.append((d[_UY], d[_UZ], float(u.amount), float(u.phase), float(ratio), m))

    def harmonic_force(omega: float, H: int) -> NDArray:
        f = np.zeros((H + 1, n), dtype=complex)
        speed = plan.speed(omega)
        for iy, iz, me, ph, ratio, m in unb:
            if m <= H:
                amp = me * (ratio * speed) ** 2 * np.exp(1j * ph)
                f[m, iy] += amp
                f[m, iz] += -1j * np.sign(ratio * speed) * amp
        return f

    orders = [lk.order for lk in links if isinstance(lk, GearMeshLink)] + [u[-1] for u in unb]
    static = np.zeros(n) if gravity is None else _gravity_force(system, assemble(system).M, gravity)
    for g in system.gear_pairs:
        static = static + g.static_torques(system)
    rec = LinkReceptance(
        system,
        links,
        plan,
        static_force=static,
        harmonic_force=harmonic_force if unb else None,
        method=loads["method"],
        max_frequency=loads["max_frequency"],
        force_dofs=[i for iy, iz, *_ in unb for i in (iy, iz)],
        top_order=max(orders, default=1),
    )
    laws = tuple(lk.law(tuple(range(sl.start, sl.stop))) for lk, sl in zip(links, rec.slices, strict=True))
    picks = [getattr(lk, "converged_outputs", None) or metric_names(lk) for lk in links]

    def outputs(harmonics: NDArray, omega: float) -> NDArray:  # what the H estimate compares
        return np.array(
            [
                m[q]
                for lk, sl, qs in zip(links, rec.slices, picks, strict=True)
                for m in (lk.metrics(harmonics[sl], omega),)
                for q in qs
            ]
        )

    def branch_signature(harmonics: NDArray, omega: float) -> NDArray:  # each contact's state
        return np.array(
            [
                lk.metrics(harmonics[sl], omega)[q]
                for lk, sl in zip(links, rec.slices, strict=True)
                for q in lk.contact_outputs
            ]
        )

    # the sweep's own per-point metrics: the first gear mesh's (the link columns hold all)
    first_mesh = next(
        (law for lk, law in zip(links, laws, strict=True) if isinstance(lk, GearMeshLink)), None
    )

    reduced = ReducedModel(
        kappa=lambda omega, H: rec.terms(omega, H)[0],
        force=lambda omega, H: rec.terms(omega, H)[1],
        nonlinearities=laws,
        state_space_at=rec.state_space,
        kappa_derivative=(lambda omega, H: rec.derivatives(omega, H)[0]) if rec.has_derivatives else None,
        force_derivative=(lambda omega, H: rec.derivatives(omega, H)[1]) if rec.has_derivatives else None,
        outputs=outputs,
        branch_signature=branch_signature,
        metrics=PointMetrics(first_mesh),
        output_scales=np.array(
            [
                getattr(lk, "output_scales", {}).get(q, 0.0)
                for lk, qs in zip(links, picks, strict=True)
                for q in qs
            ]
        ),
    )
    return LinkModel(system, links, rec, reduced, max(orders, default=1), period, dict(loads))


#: Newton iterations per sweep point (the default of :func:`link_sweep`): the Jacobian
#: jumps where contact is first lost (grazing), where damped Newton can need a hundred
#: iterations, each cheap. Kahraman & Blankenship's rig at 3600 Hz, H = 5, one point from
#: the linear response: 89 iterations on the link reduction (52 on the mesh-coordinate
#: one, the same equations to 1e-10); with 50 the point was lost.
SWEEP_MAX_ITER = 150


def check_stability_damping(system: RotorSystem, stability: bool) -> None:
    """Refuse Floquet stability of a model with hysteretic damping, naming the material.

    A loss factor has no time-domain form (its force is in quadrature with the
    displacement at every frequency at once), so the state space of the stability analysis
    has none (:meth:`~nlgrd.nonlinear.reduction.link_reduction.LinkReceptance.state_space`).

    Parameters
    ----------
    system : RotorSystem
        The model.
    stability : bool
        Whether Floquet stability is asked for.

    Raises
    ------
    ModelError
        (``materials.<name>.loss_factor``) A material with a loss factor, with stability.
    """
    if not stability:
        return
    for shaft in system.shafts:
        for el in shaft.elements:
            mat = el.material
            if mat.loss_factor > 0:
                raise ModelError(
                    f"materials.{mat.name}.loss_factor",
                    f"{mat.loss_factor!r}: {HYSTERETIC_REFUSAL} (stability=False, --no-stability)",
                )


def link_sweep(
    model: LinkModel,
    omegas: NDArray,
    H: int | None = None,
    *,
    rtol: float = OUTPUT_RTOL,
    period: int | str = "auto",
    **options,
) -> LinkSweepResult:
    """Harmonic-balance sweep of a link model with the links' outputs.

    Parameters
    ----------
    model : LinkModel
        From :func:`build_link_model`.
    omegas : array_like
        Base frequencies [rad/s].
    H : int, optional
        Number of harmonics [-]. By default chosen by the error estimate of
        :func:`nlgrd.nonlinear.tracing.harmonic_convergence.converged_sweep` on the ladder
        :data:`~nlgrd.nonlinear.tracing.harmonic_convergence.LADDER` times the model's
        ``top_order`` (so a mesh at base harmonic m gets 5 m, 7 m, ... harmonics), comparing
        every link's ``converged_outputs``; the result carries the estimate per point.
    rtol : float
        The tolerance of the estimated relative error of the outputs [-] (with H chosen,
        and of the period-2 points always).
    period : {"auto", 1, 2}
        In base periods. "auto" (default, as ``nlgrd.sweep``, ``nlgrd sweep`` and the
        studies): the period-1 orbits where they are stable and, where one has lost
        stability by period doubling (a real Floquet multiplier < -1), the stable period-2
        orbit (:func:`nlgrd.nonlinear.tracing.auto_period.beyond_period_one` on
        :func:`period_model`, 2 H harmonics of ω/2); without ``stability`` it is 1. It
        costs more than 1 only where a period doubling is found. 1: period-1 orbits only,
        every point's harmonics those of ω (what a caller that starts time integrations
        or recoveries on the period-1 model from the harmonics asks for). 2: the period-2
        branches alone (needs ``stability``).
    **options
        Passed to :func:`nlgrd.nonlinear.tracing.sweep.sweep` (``directions``, ``tol``,
        ``stability`` (default True), ``jump``, ``max_iter`` (default :data:`SWEEP_MAX_ITER`), ...).

    Returns
    -------
    LinkSweepResult
        With period-2 points the harmonics are of ω/2 (period-1 ones spread onto it) and
        the links' outputs are over the whole period 2T; ``result.period`` per point.

    Raises
    ------
    ModelError
        A ``period`` other than 1, 2 or "auto", or 2 without stability.
    """
    period_iter = options.get("max_iter", 50)  # the period-2 solves' own default
    options.setdefault("stability", True)
    options.setdefault("jump", "auto")
    options.setdefault("max_iter", SWEEP_MAX_ITER)
    check_period(period, options["stability"])
    check_stability_damping(model.system, options["stability"])
    omegas = np.asarray(omegas, dtype=float)
    top = float(np.max(np.abs(omegas))) if omegas.size else 0.0
    ladder = [h * model.top_order for h in LADDER]
    model.receptance.prepare_stability(top)  # the stability basis serves the whole sweep
    if H is None:

        def on_rung(h):  # a modal basis (large models) serves the check's H' too
            if top > 0:
                model.receptance.prepare(next_harmonics(h, ladder) * top)

        res = converged_sweep(model.reduced, omegas, rtol=rtol, ladder=ladder, on_rung=on_rung, **options)
    else:
        if top > 0:  # a modal basis (large models) serves H x the highest frequency
            model.receptance.prepare(H * top)
        res = sweep(model.reduced, omegas, H, **options)
    p1, p2 = res, None
    if period != 1 and options["stability"]:
        H_check = 2 * next_harmonics(p1.H, ladder)  # of ω/2: the check of 2 H harmonics

        def reduced2() -> ReducedModel:
            two = period_model(model, 2)
            if top > 0:
                two.receptance.prepare(H_check * top / 2)
                two.receptance.prepare_stability(top / 2)
            return two.reduced

        res, p2 = beyond_period_one(
            p1,
            period,
            reduced2,
            omegas,
            options.get("directions", "both"),
            H_check,
            rtol,
            tol=options.get("tol", 1e-10),
            max_iter=period_iter,
        )
    two = period_model(model, 2) if p2 is not None else None
    blank = dict.fromkeys(output_names(model), np.nan)
    rows = [blank] * len(res)
    # a period-2 point over 2T on the base ω/2, a period-1 one on its own harmonics; the
    # points of each model at once
    ok = [i for i in range(len(res)) if res.converged[i] and not res.no_stable[i]]
    on_two = [i for i in ok if two is not None and int(res.period[i]) == 2]
    on_one = [i for i in ok if i not in set(on_two)]
    # the first mesh's metrics of the period-1 points: the sweep's own (the same function
    # of the same harmonics, its contact intervals found while solving)
    first = next((lk for lk in model.links if isinstance(lk, GearMeshLink)), None)
    known = None
    if first is not None and "n_samples" not in options:
        known = {first.name: [GearMeshLink.metric_row(p1.metrics, i) for i in on_one]}
    for m, pts, zs, ws, kn in (
        (model, on_one, [p1.harmonics[i] for i in on_one], [res.omega[i] for i in on_one], known),
        (two, on_two, [res.harmonics[i] for i in on_two], [res.omega[i] / 2 for i in on_two], None),
    ):
        if pts:
            for i, row in zip(pts, points_outputs(m, zs, ws, kn), strict=True):
                rows[i] = row
    columns = {c: np.array([row[c] for row in rows], dtype=float) for c in blank}  # faster than rows
    table = pd.DataFrame(columns, columns=list(blank))
    table = with_amplitudes(table, model, res, np.isin(np.arange(len(res)), ok))
    return LinkSweepResult(res, table, bearing_columns(model))


def link_continuation(
    model: LinkModel,
    omega_start: float,
    omega_end: float,
    H: int | None = None,
    *,
    rtol: float = OUTPUT_RTOL,
    **options,
) -> LinkContinuationResult:
    """Pseudo-arc-length continuation of a link model with the links' outputs.

    Parameters
    ----------
    model : LinkModel
        From :func:`build_link_model`.
    omega_start, omega_end : float
        Base frequencies where the curve starts and towards which it goes [rad/s].
    H : int, optional
        Harmonics of the base [-]; default chosen by the error estimate
        (:func:`~nlgrd.nonlinear.tracing.harmonic_convergence.converged_continuation` on the
        ladder times the model's ``top_order``, as :func:`link_sweep`).
    rtol : float
        Tolerance of the estimated relative error of the outputs when H is chosen [-].
    **options
        Further options of :func:`nlgrd.nonlinear.tracing.continuation.continuation`
        (``stability``, ``ds_max``, ...).

    Returns
    -------
    LinkContinuationResult
    """
    check_stability_damping(model.system, options.get("stability", True))
    top = max(abs(float(omega_start)), abs(float(omega_end)))
    model.receptance.prepare_stability(top)
    if H is None:
        ladder = [h * model.top_order for h in LADDER]
        model.receptance.prepare(ladder[-1] * top)
        res = converged_continuation(
            model.reduced, omega_start, omega_end, rtol=rtol, ladder=ladder, **options
        )
    else:
        model.receptance.prepare(int(H) * top)
        res = continuation(model.reduced, omega_start, omega_end, int(H), **options)
    usable = np.asarray(res.curve.converged, dtype=bool)
    links = with_amplitudes(link_rows(model, res.curve, usable), model, res.curve, usable)
    return LinkContinuationResult(res, links)


def needs_links(system) -> bool:
    """Whether ``system`` needs the link path (several meshes, a bearing clearance or an
    unbalance).

    Parameters
    ----------
    system : RotorSystem
        The model.

    Returns
    -------
    bool
    """
    return len(system.gear_pairs) != 1 or bool(system.bearing_clearances) or bool(system.unbalance)

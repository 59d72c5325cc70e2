"""A rotor model with any number of nonlinear links: build, sweep, per-link outputs.

:func:`build_link_model` reduces a :class:`~nlgrd.rotor.system.RotorSystem` onto the
coordinates of its links (:mod:`nlgrd.nonlinear.link_reduction`) with unbalance and
gravity as loads; :func:`link_sweep` runs the harmonic-balance sweep of
:func:`nlgrd.nonlinear.sweep.sweep` on it, with Floquet stability, and writes every
link's outputs in columns named ``<link>.<quantity>``.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import pandas as pd
from numpy.typing import NDArray

from nlgrd.errors import ModelError
from nlgrd.nonlinear.frequency_plan import FrequencyPlan
from nlgrd.nonlinear.harmonic_balance import ReducedModel
from nlgrd.nonlinear.harmonic_convergence import LADDER, OUTPUT_RTOL, converged_sweep, next_harmonics
from nlgrd.nonlinear.link_reduction import LinkReceptance
from nlgrd.nonlinear.links import GearMeshLink
from nlgrd.nonlinear.results import SweepResult
from nlgrd.nonlinear.sweep import sweep
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
    """

    system: RotorSystem
    links: tuple
    receptance: LinkReceptance
    reduced: ReducedModel
    top_order: int = 1

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
    """
    unbalance = system.unbalance if unbalance is None else tuple(unbalance)
    unb_orders = [abs(system.shafts[u.shaft].speed_ratio) for u in unbalance]
    plan = plan or FrequencyPlan.for_system(system, unb_orders)
    links = list(links) + list(system.bearing_clearances)
    given = {lk.index for lk in links if isinstance(lk, GearMeshLink) and lk.index is not None}
    links += [lk for lk in gear_links(system, plan) if lk.index not in given]
    links = tuple(links)
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

    static = np.zeros(n) if gravity is None else _gravity_force(system, assemble(system).M, gravity)
    for g in system.gear_pairs:
        static = static + g.static_torques(system)
    rec = LinkReceptance(
        system,
        links,
        plan,
        static_force=static,
        harmonic_force=harmonic_force if unb else None,
        method=method,
        max_frequency=max_frequency,
        force_dofs=[i for iy, iz, *_ in unb for i in (iy, iz)],
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

    reduced = ReducedModel(
        kappa=lambda omega, H: rec.terms(omega, H)[0],
        force=lambda omega, H: rec.terms(omega, H)[1],
        nonlinearities=laws,
        state_space_at=rec.state_space,
        kappa_derivative=(lambda omega, H: rec.derivatives(omega, H)[0]) if rec.has_derivatives else None,
        force_derivative=(lambda omega, H: rec.derivatives(omega, H)[1]) if rec.has_derivatives else None,
        outputs=outputs,
    )
    orders = [lk.order for lk in links if isinstance(lk, GearMeshLink)] + [u[-1] for u in unb]
    return LinkModel(system, links, rec, reduced, max(orders, default=1))


@dataclass(frozen=True)
class LinkSweepResult:
    """A sweep of a link model: the harmonic-balance points and every link's outputs.

    Attributes
    ----------
    result : SweepResult
        The points (harmonics of all link coordinates, convergence, stability).
    links : pandas.DataFrame
        One row per point: ``<link>.<quantity>`` columns; NaN where the point did not
        converge or has no stable periodic response.
    """

    result: SweepResult
    links: pd.DataFrame

    def to_frame(self) -> pd.DataFrame:
        """The sweep's table (frequency column ``base_frequency [Hz]``) with the link columns.

        Returns
        -------
        pandas.DataFrame
        """
        frame = self.result.to_frame()
        drop = [c for c in frame.columns if c.startswith(("dte_", "force_", "dslr", "contact_loss", "back_"))]
        frame = frame.drop(columns=drop).rename(columns={"mesh_frequency [Hz]": "base_frequency [Hz]"})
        return pd.concat([frame, self.links], axis=1)

    def jumps(self, quantities: str | Sequence[str] | None = None, rtol: float = 0.1, ratio: float = 3.0):
        """Jumps of each sweep direction in the links' outputs (:meth:`SweepResult.jumps`
        on the columns of :attr:`links`).

        Parameters
        ----------
        quantities : str or sequence of str, optional
            ``<link>.<quantity>`` columns; default every column.
        rtol, ratio : float
            As :func:`nlgrd.nonlinear.jumps.find_jumps` [-].

        Returns
        -------
        list of Jump
        """
        if quantities is None:
            quantities = list(self.links.columns)
        qs = [quantities] if isinstance(quantities, str) else list(quantities)
        for q in qs:
            if q not in self.links.columns:
                raise ModelError(
                    "quantities", f"no link output {q!r}; the columns are {list(self.links.columns)}"
                )
        return self.result.jumps_of({q: self.links[q].to_numpy() for q in qs}, rtol, ratio)


def metric_names(link) -> list[str]:
    """The names (with units) of a link's per-point outputs, in its ``metrics`` order.

    Parameters
    ----------
    link : NonlinearLink
        The link.

    Returns
    -------
    list of str
    """
    return list(link.metrics(np.zeros((link.n_coords, 3)), 1.0))


def link_sweep(
    model: LinkModel, omegas: NDArray, H: int | None = None, *, rtol: float = OUTPUT_RTOL, **options
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
        :func:`nlgrd.nonlinear.harmonic_convergence.converged_sweep` on the ladder
        :data:`~nlgrd.nonlinear.harmonic_convergence.LADDER` times the model's
        ``top_order`` (so a mesh at base harmonic m gets 5 m, 7 m, ... harmonics), comparing
        every link's ``converged_outputs``; the result carries the estimate per point.
    rtol : float
        With H chosen: the tolerance of the estimated relative error of the outputs [-].
    **options
        Passed to :func:`nlgrd.nonlinear.sweep.sweep` (``directions``, ``tol``,
        ``stability`` (default True), ``jump``, ...).

    Returns
    -------
    LinkSweepResult
    """
    options.setdefault("stability", True)
    options.setdefault("jump", "auto")
    omegas = np.asarray(omegas, dtype=float)
    top = float(np.max(np.abs(omegas))) if omegas.size else 0.0
    if H is None:
        ladder = [h * model.top_order for h in LADDER]

        def on_rung(h):  # a modal basis (large models) serves the check's H' too
            if top > 0:
                model.receptance.prepare(next_harmonics(h, ladder) * top)

        res = converged_sweep(
            model.reduced, omegas, rtol=rtol, ladder=ladder, on_rung=on_rung, mesh=None, **options
        )
    else:
        if top > 0:  # a modal basis (large models) serves H x the highest frequency
            model.receptance.prepare(H * top)
        res = sweep(model.reduced, omegas, H, mesh=None, **options)
    rows = []
    for i in range(len(res)):
        row = {}
        ok = bool(res.converged[i]) and not bool(res.no_stable[i])
        for link, sl in zip(model.links, model.receptance.slices, strict=True):
            if ok:
                values = link.metrics(res.harmonics[i][sl], float(res.omega[i]))
            else:
                values = dict.fromkeys(metric_names(link), np.nan)
            row.update({f"{link.name}.{k}": v for k, v in values.items()})
        rows.append(row)
    return LinkSweepResult(res, pd.DataFrame(rows))


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

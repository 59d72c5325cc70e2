"""Quasi-periodic answers of a model: tori followed in speed.

Where a periodic orbit has lost stability to a complex pair of Floquet multipliers
μ = |μ| e^{±iθ} (a Neimark-Sacker bifurcation), the response is a torus with the base
frequency ω₁ and a secondary frequency ω₂ ≈ θ ω₁ / 2π. This module follows it by the
two-frequency harmonic balance of :mod:`nlgrd.nonlinear.hb.quasi_periodic` (continuation
in speed, starts from the critical Floquet mode, the ladder of H₁) and reports per point
its outputs and their change from (H₁, H₂) to (H₁ + 4, H₂ + 2). What is solved and
reported comes from a target: :class:`~nlgrd.nonlinear.tracing.link_torus.LinkTorus` (all
link coordinates of a link model, one mesh too: the default); the sweep asks nothing else
of the model.
"""

from __future__ import annotations

import dataclasses as dc
from dataclasses import dataclass

import numpy as np
import pandas as pd
from numpy.typing import NDArray

from nlgrd.errors import ModelError
from nlgrd.nonlinear.fourier.harmonics import real_to_complex
from nlgrd.nonlinear.hb import quasi_periodic as qp
from nlgrd.nonlinear.hb import torus_grid as tg
from nlgrd.nonlinear.hb.solvers import solve
from nlgrd.nonlinear.stability.floquet_mode import dominant_floquet_mode
from nlgrd.nonlinear.tracing.link_torus import LinkTorus
from nlgrd.nonlinear.tracing.torus_outputs import CHECKED, TORUS_OUTPUTS
from nlgrd.units import column, hz

#: Largest relative speed step continued from the previous torus; beyond it the torus is
#: started afresh from the periodic orbit.
CONTINUATION_STEP = 0.02
#: Starts tried, as fractions of the periodic orbit's first-harmonic amplitude.
START_SIZES = (0.02, 0.1, 0.005, 0.3)


@dataclass(frozen=True)
class TorusResult:
    """Tori of a model over speed, one row per speed.

    Attributes
    ----------
    omega : ndarray (n,)
        Base frequency ω₁ (one mesh: the mesh frequency) [rad/s].
    rpm : ndarray (n,)
        Reference shaft speed [rpm].
    converged : ndarray of bool (n,)
        A torus was found (False where the periodic orbit is stable or Newton failed).
    outputs : ndarray (n, len(TORUS_OUTPUTS))
        :func:`torus_outputs` per point (SI); NaN where not converged.
    change : ndarray (n, len(CHECKED))
        Relative change of the :data:`CHECKED` outputs from (H, H2) to (H + 4, H2 + 2): the
        convergence estimate [-]; NaN where not checked.
    multiplier : ndarray of complex (n,)
        The periodic orbit's dominant Floquet multiplier where the torus was started from
        it [-] (NaN elsewhere).
    residual : ndarray (n,)
        Relative residual of the torus balance [-].
    iterations : ndarray of int (n,)
        Newton iterations [-].
    seconds : ndarray (n,)
        Wall time per point, the check included [s].
    H, H2 : int
        Harmonics of ω₁ and of ω₂ [-].
    bearing_force_max : ndarray (n, n_bearings)
        The largest force of every bearing over the torus per point [N].
    bearing_names : list of str
        The bearings' names, as the sweep's columns.
    solutions : list
        The :class:`~nlgrd.nonlinear.hb.quasi_periodic.TorusSolution` per point (None where
        not converged).
    error : ndarray (n,), optional
        The convergence estimate per point: the largest of ``change`` for one mesh, the
        largest over every link's checked outputs and ω₂ for a link model [-]; NaN where
        not checked (default: the largest of ``change``).
    meshes : tuple of str
        Every gear mesh's link name, the first the one ``outputs`` holds (none: a model
        without a gear mesh; default ``("mesh0",)``).
    mesh_outputs : ndarray (n, len(meshes), len(TORUS_OUTPUTS)), optional
        Every mesh's :func:`torus_outputs` per point (SI); default ``outputs`` as the one
        mesh's.
    mesh_change : ndarray (n, len(meshes), len(CHECKED)), optional
        Every mesh's ``change`` [-]; default ``change`` as the one mesh's.
    """

    omega: NDArray
    rpm: NDArray
    converged: NDArray
    outputs: NDArray
    change: NDArray
    multiplier: NDArray
    residual: NDArray
    iterations: NDArray
    seconds: NDArray
    H: int
    H2: int
    bearing_force_max: NDArray
    bearing_names: list
    solutions: list
    error: NDArray | None = None
    meshes: tuple = ("mesh0",)
    mesh_outputs: NDArray | None = None
    mesh_change: NDArray | None = None

    def __post_init__(self):
        if self.error is None:
            object.__setattr__(self, "error", np.max(np.abs(self.change), axis=1))
        for name, one in (("mesh_outputs", self.outputs), ("mesh_change", self.change)):
            if getattr(self, name) is None:
                if len(self.meshes) > 1:
                    raise ModelError(name, f"every mesh's values are needed for {len(self.meshes)} meshes")
                object.__setattr__(self, name, np.asarray(one)[:, None, :][:, : len(self.meshes)])

    def output(self, name: str) -> NDArray:
        """One output column (SI).

        Parameters
        ----------
        name : str
            One of :data:`TORUS_OUTPUTS`.

        Returns
        -------
        ndarray (n,)
        """
        if name not in TORUS_OUTPUTS:
            raise ModelError("name", f"one of {tuple(TORUS_OUTPUTS)}, got {name!r}")
        return self.outputs[:, list(TORUS_OUTPUTS).index(name)]

    def to_frame(self) -> pd.DataFrame:
        """The table (docs/conventions.md, "Column names"): ``base_frequency [Hz]``,
        ``shaft_speed [rpm]``, every gear mesh's outputs ``<mesh>.<quantity> [unit]``
        (``<mesh>.dte_rms [um]``, ``<mesh>.force_max [N]``, ...), ``secondary_frequency [Hz]``,
        every mesh's convergence changes ``<mesh>.dte_rms_change [-]`` and
        ``<mesh>.force_max_change [-]``, ``secondary_frequency_change [-]``, ``torus_error [-]``
        (the largest convergence change), ``<bearing>.force_max [N]`` and ``floquet_max [-]``
        (the periodic orbit's |μ| where the torus was started from it).

        Returns
        -------
        pandas.DataFrame
        """
        cols = {
            "base_frequency [Hz]": hz(self.omega),
            "shaft_speed [rpm]": self.rpm,
            "response": np.where(self.converged, "quasi-periodic", ""),
            "converged": self.converged,
            "residual [-]": self.residual,
            "iterations": self.iterations,
            "H": self.H,
            "H2": self.H2,
        }
        names = list(TORUS_OUTPUTS)
        for m, mesh in enumerate(self.meshes):
            for j, (name, (unit, factor)) in enumerate(TORUS_OUTPUTS.items()):
                if name != "secondary_frequency":  # of the torus, not of a mesh
                    cols[column(name, unit, mesh)] = self.mesh_outputs[:, m, j] * factor
        unit, factor = TORUS_OUTPUTS["secondary_frequency"]
        secondary = self.outputs[:, names.index("secondary_frequency")]
        cols[column("secondary_frequency", unit)] = secondary * factor
        for m, mesh in enumerate(self.meshes):
            for j, name in enumerate(CHECKED):
                if name != "secondary_frequency":
                    cols[column(f"{name}_change", "-", mesh)] = self.mesh_change[:, m, j]
        cols["secondary_frequency_change [-]"] = self.change[:, list(CHECKED).index("secondary_frequency")]
        cols["torus_error [-]"] = self.error
        for j, name in enumerate(self.bearing_names):
            cols[column("force_max", "N", name)] = self.bearing_force_max[:, j]
        cols["floquet_max [-]"] = np.abs(self.multiplier)
        cols["seconds [s]"] = self.seconds
        return pd.DataFrame(cols)

    def plot(self, quantity: str = "dte_rms", ax=None):
        """One output of the tori against the reference shaft speed, open squares as a
        sweep draws a torus answer, a speed without a torus a cross on the bottom edge
        (:func:`nlgrd.plotting.result_figures.plot_tori`).

        Parameters
        ----------
        quantity : str
            A column's quantity of :meth:`to_frame`: ``MESH.QUANTITY`` or a bare quantity
            (the first mesh's: ``dte_rms``, ``secondary_frequency``, ...).
        ax : matplotlib.axes.Axes, optional
            Axes to draw on; a new figure when None.

        Returns
        -------
        matplotlib.axes.Axes
        """
        from nlgrd.plotting.result_figures import plot_tori

        return plot_tori(self.to_frame(), quantity, ax=ax)


def _periodic(reduced, omega: float, H: int, start: NDArray | None) -> NDArray | None:
    """Real harmonics (n_c, 2H+1) of the periodic orbit at ``omega`` from ``start``."""
    sol = solve(reduced.at(omega, H), start)
    return sol.harmonics if sol.converged else None


def _start_torus(
    tm, reduced, omega: float, Zp: NDArray, grid, max_iter: int = 60, sizes: tuple | None = None
) -> tuple[qp.TorusSolution | None, complex]:
    """A torus from the periodic orbit and its critical Floquet mode, or None when the orbit
    has no complex pair outside the unit circle."""
    ss = reduced.linear_state_space(omega)
    mu = dominant_floquet_mode(ss, reduced.nonlinearities, Zp, omega).multiplier
    if abs(mu) <= 1 + 1e-6 or abs(mu.imag) <= 1e-6 * abs(mu):
        return None, mu
    w2 = qp.secondary_from_multiplier(mu, omega)
    Yp = np.stack([real_to_complex(z) for z in np.atleast_2d(Zp)])
    shape = qp.critical_shape(tm, omega, Yp, w2, grid.H1)
    base = float(np.abs(Yp[:, 1:]).max())
    for size in START_SIZES if sizes is None else sizes:
        sol = qp.solve_torus(
            tm, omega, grid, qp.periodic_start(Yp, grid, shape, size * base), w2, max_iter=max_iter
        )
        if sol.converged:
            return sol, mu
    return None, mu


def torus_sweep(
    model,
    omegas: NDArray | None = None,
    *,
    rpm: NDArray | None = None,
    H: int = 13,
    H2: int = 4,
    periodic: NDArray | None = None,
    check: bool = True,
    tol: float = 1e-8,
    max_iter: int = 60,
    start_sizes: tuple | None = None,
    progress=None,
    target=None,
    check_step: int = 1,
) -> TorusResult:
    """Tori of a model at the given speeds, in their order (natural continuation).

    At the first speed (and after any speed without a torus) the periodic orbit is solved
    (from ``periodic`` when given, e.g. a sweep's stored harmonics of the points it marked
    quasi-periodic), its dominant Floquet multiplier computed, and where it is a complex
    pair outside the unit circle the torus started from the critical mode
    (:func:`~nlgrd.nonlinear.hb.quasi_periodic.critical_shape`) at ω₂ = |arg μ| ω₁ / 2π. Further
    speeds start from the previous torus, extrapolated linearly from the last two, with it as
    the phase reference (within ``CONTINUATION_STEP`` of the previous speed; farther, afresh).

    Parameters
    ----------
    model : LinkModel
        From :func:`nlgrd.nonlinear.models.link_model.build_link_model` (period 1), one mesh
        too; another model with its ``target``.
    omegas : array_like, optional
        Base frequencies [rad/s]; or
    rpm : array_like, optional
        reference shaft speeds [rpm].
    H : int
        Harmonics of the base frequency H₁ (the periodic sweep's H) [-].
    H2 : int
        Harmonics of the secondary frequency H₂ [-].
    periodic : ndarray (n, 1, 2H+1), optional
        Real harmonics of the (unstable) periodic orbit per speed [m], starts of its solve.
    check : bool
        Also solve at (H + 4, H2 + 2) for the convergence estimate.
    tol : float
        Relative residual of the torus balance [-].
    max_iter : int
        Newton iterations of each solve [-].
    start_sizes : tuple of float, optional
        The starts tried from the periodic orbit (default :data:`START_SIZES`) [-].
    progress : callable (done, total), optional
        Called after each speed.
    target : LinkTorus, optional
        What is solved and reported (default ``LinkTorus(model)``).
    check_step : int
        The check is at (H + 4 ``check_step``, H2 + 2): a link model's ``top_order`` [-].

    Returns
    -------
    TorusResult
        One row per speed.

    Raises
    ------
    ModelError
        Neither or both of ``omegas`` and ``rpm``; a model of period > 1.
    """
    import time  # noqa: PLC0415

    if (omegas is None) == (rpm is None):
        raise ModelError("rpm", "give exactly one of omegas [rad/s] and rpm")
    target = LinkTorus(model) if target is None else target
    omegas = np.atleast_1d(np.asarray(target.omegas(rpm) if omegas is None else omegas, dtype=float))
    n = omegas.size
    tm = target.torus_model
    grid = tg.TorusGrid(H, H2, *tg.default_grid(H, H2))
    Hc = H + 4 * int(check_step)
    if hasattr(target, "prepare") and n:  # a modal basis up to the check's top harmonic
        target.prepare((Hc if check else H) * float(np.max(np.abs(omegas))) * 1.0001)
    fine = tg.TorusGrid(Hc, H2 + 2, *tg.default_grid(Hc, H2 + 2)) if check else None
    out = np.full((n, len(TORUS_OUTPUTS)), np.nan)
    change = np.full((n, len(CHECKED)), np.nan)
    mult = np.full(n, np.nan + 0j)
    res, its, secs = np.full(n, np.nan), np.zeros(n, dtype=int), np.zeros(n)
    sols: list = [None] * n
    names = target.bearing_names
    meshes = tuple(target.mesh_names)
    mesh_out = np.full((n, len(meshes), len(TORUS_OUTPUTS)), np.nan)
    mesh_ch = np.full((n, len(meshes), len(CHECKED)), np.nan)
    bear = np.full((n, len(names)), np.nan)
    error = np.full(n, np.nan)
    hist: list[tuple[float, qp.TorusSolution]] = []
    Zp = None
    if progress is not None:  # the bar from the start: a torus takes seconds
        progress(0, n)
    for i, w in enumerate(omegas):
        t0 = time.perf_counter()
        sol = None
        if hist and abs(w - hist[-1][0]) > CONTINUATION_STEP * w:
            hist = []  # a gap in speed (another band): start afresh
        if hist:
            (wa, sa) = hist[-1]
            Y0, w2 = sa.Y, sa.secondary
            if len(hist) > 1:
                (wb, sb) = hist[-2]
                r = (w - wa) / (wa - wb)
                Y0, w2 = sa.Y + r * (sa.Y - sb.Y), sa.secondary + r * (sa.secondary - sb.secondary)
            sol = qp.solve_torus(tm, float(w), grid, Y0, w2, Y_ref=sa.Y, tol=tol, max_iter=max_iter)
            if not sol.converged and len(hist) > 1:  # without the predictor
                sol = qp.solve_torus(tm, float(w), grid, sa.Y, sa.secondary, tol=tol, max_iter=max_iter)
        if sol is None or not sol.converged:
            start = periodic[i] if periodic is not None else Zp
            Zp = _periodic(target.reduced, float(w), H, start)
            if Zp is not None:
                sol, mult[i] = _start_torus(tm, target.reduced, float(w), Zp, grid, max_iter, start_sizes)
        if sol is not None and sol.converged:
            sols[i] = sol
            hist = (hist + [(float(w), sol)])[-2:]
            out[i] = target.outputs(sol)
            mesh_out[i] = target.mesh_outputs(sol, out[i]) if meshes else mesh_out[i]
            bear[i] = target.bearing_force_max(sol)
            res[i], its[i] = sol.residual, sol.iterations
            if fine is not None:
                big = qp.solve_torus(
                    tm,
                    float(w),
                    fine,
                    tg.resize(sol.Y, grid, fine),
                    sol.secondary,
                    tol=tol,
                    max_iter=max_iter,
                )
                if big.converged:
                    change[i], error[i] = target.change(out[i], sol, big)
                    mesh_ch[i] = target.mesh_change(mesh_out[i], big) if meshes else mesh_ch[i]
        else:
            hist = []
        secs[i] = time.perf_counter() - t0
        if progress is not None:
            progress(i + 1, n)
    return TorusResult(
        omegas,
        target.rpm(omegas),
        np.array([s is not None for s in sols]),
        out,
        change,
        mult,
        res,
        its,
        secs,
        int(H),
        int(H2),
        bear,
        names,
        sols,
        error,
        meshes,
        mesh_out,
        mesh_ch,
    )


#: Raises of H₁ over the sweep's H tried until a torus's convergence estimate meets the
#: tolerance (each rung checked at H₁ + 4, H₂ + 2).
TORUS_LADDER = (0, 4, 8)
#: Largest H₁ of the ladder (the model is built for it + 4).
TORUS_MAX_H = 17
#: Newton iterations of a sweep's torus solve: Kubo's tori converge in 3-12 from the
#: critical mode or the previous torus (benchmarks/torus_kubo_reference*.csv), K&B's in
#: 4-17; a start that has not converged by then is abandoned (a chaotic band costs 60 a
#: start otherwise), one whose residual stalls sooner (quasi_periodic.STALL_STEPS).
ANSWER_MAX_ITER = 25
#: Relative residual of a sweep's torus solve: below the default 1e-8, so that the noise
#: its start carries (the Floquet mode's last bits) stays far below the digits written.
ANSWER_TOL = 1e-10
#: Largest number of real unknowns of a sweep's torus check, (H₁ + 4 step, H₂ + 2) on all
#: coordinates: its dense Jacobian (8 bytes each, squared: 128 MB at 4000) and the
#: O(|𝒦|²) AFT tangent blocks bound the memory; a rung above it is not tried (the point
#: goes on to the time answer). One mesh at H₁ 17 checks 559; a two-mesh train whose base
#: is the shaft speed (``top_order`` 20) would need ~9000.
TORUS_MAX_UNKNOWNS = 4000
#: The starts a sweep's torus tries from the periodic orbit (the first two of
#: :data:`START_SIZES`; the first started every Kubo torus of the reference band).
ANSWER_START_SIZES = START_SIZES[:2]


@dataclass(frozen=True)
class TorusAnswer:
    """A torus accepted as a sweep point's answer (:func:`converged_tori`).

    Attributes
    ----------
    solution : TorusSolution
        The torus at (H₁, H₂).
    outputs : dict of str to float
        :data:`TORUS_OUTPUTS` (SI) and ``back_contact``.
    bearings : dict of str to ndarray
        :func:`~nlgrd.nonlinear.tracing.torus_outputs.torus_bearing_statistics`.
    error : float
        Its convergence estimate: the largest relative change of the :data:`CHECKED`
        outputs from (H₁, H₂) to (H₁ + 4, H₂ + 2) [-].
    H : int
        H₁, harmonics of the mesh frequency [-].
    H2 : int
        Harmonics of the secondary frequency [-].
    seconds : float
        Wall time of its rungs, checks included [s].
    columns : dict of str to float
        A link model's columns ``<link>.<quantity> [unit]`` and its linear bearings'
        (:func:`nlgrd.nonlinear.tracing.link_torus.torus_link_columns`); empty for one mesh.
    """

    solution: qp.TorusSolution
    outputs: dict
    bearings: dict
    error: float
    H: int
    H2: int
    seconds: float
    columns: dict = dc.field(default_factory=dict)


def converged_tori(
    model,
    omegas: NDArray,
    periodic: NDArray,
    *,
    H: int,
    rtol: float,
    H2: int = 4,
    progress=None,
    target=None,
    step: int = 1,
) -> list:
    """Tori at consecutive points of a sweep (in its order) whose convergence estimate is
    within ``rtol``: :func:`torus_sweep` with its check at H₁ = H, then at the rungs of
    :data:`TORUS_LADDER` for the points whose torus and its check converged but missed
    ``rtol`` (a point without a torus at H₁ is not sought higher), each followed from the previous
    point's torus where the points are consecutive (within ``CONTINUATION_STEP``) and
    started from the periodic orbit's critical Floquet mode elsewhere. The torus's
    stability is not computed.

    Parameters
    ----------
    model : LinkModel
        Period 1; its receptance prepared for the top rung + 4 ``step`` harmonics.
    omegas : ndarray (n,)
        Base frequencies, in the sweep's order [rad/s].
    periodic : ndarray (n, n_c, 2H+1)
        The (unstable) periodic orbits there, starts of the periodic solve [m].
    H : int
        The sweep's H [-].
    rtol : float
        The sweep's tolerance on its outputs [-].
    H2 : int
        Harmonics of the secondary frequency [-].
    progress : callable (done, total), optional
        Called after each point of each rung (``total`` the points of the rung).
    target : LinkTorus, optional
        What is solved and reported (:func:`torus_sweep`; default ``LinkTorus(model)``).
    step : int
        The rungs of :data:`TORUS_LADDER` are H + ``step`` x rung and the check
        H₁ + 4 ``step`` (a link model's ``top_order``: its mesh at base harmonic ``step``)
        [-]; a rung whose check exceeds :data:`TORUS_MAX_UNKNOWNS` is not tried.

    Returns
    -------
    list of TorusAnswer or None
        Per point; None where no torus converged within ``rtol`` on any rung.
    """
    import time  # noqa: PLC0415

    n = len(omegas)
    answers: list = [None] * n
    spent = np.zeros(n)
    pending = np.arange(n)
    target = LinkTorus(model) if target is None else target
    step = int(step)
    rungs = [H + step * r for r in TORUS_LADDER if H + step * r <= max(H, step * TORUS_MAX_H)]
    z_all = np.asarray(periodic, dtype=float)
    z_all = z_all.reshape(len(omegas), -1, z_all.shape[-1])
    n_c = z_all.shape[1]
    rungs = [h for h in rungs if n_c * tg.TorusGrid.n_real_of(h + 4 * step, H2 + 2) <= TORUS_MAX_UNKNOWNS]
    for Hr in rungs:
        if not pending.size:
            break
        z = z_all[pending]
        starts = np.zeros((pending.size, z.shape[1], 2 * Hr + 1))
        m = min(z.shape[2], 2 * Hr + 1)
        starts[:, :, :m] = z[:, :, :m]
        res = torus_sweep(
            model,
            np.asarray(omegas, dtype=float)[pending],
            H=Hr,
            H2=H2,
            periodic=starts,
            tol=ANSWER_TOL,
            max_iter=ANSWER_MAX_ITER,
            start_sizes=ANSWER_START_SIZES,
            target=target,
            check_step=step,
            progress=progress,
        )
        spent[pending] += res.seconds
        err = res.error  # NaN: the check did not converge
        for row, i in enumerate(pending):
            sol = res.solutions[row]
            if sol is not None and np.isfinite(err[row]) and err[row] <= rtol:
                t0 = time.perf_counter()
                out, bearings, columns = target.answer(sol, res.outputs[row])
                spent[i] += time.perf_counter() - t0
                answers[i] = TorusAnswer(sol, out, bearings, float(err[row]), Hr, H2, 0.0, columns)
        # only a torus found but short of the tolerance climbs: one not found at H₁ (no
        # torus near the orbit, e.g. a chaotic band) is not sought again at a higher H₁
        climb = [i for row, i in enumerate(pending) if answers[i] is None and np.isfinite(err[row])]
        pending = np.array(climb, dtype=int)
    return [None if a is None else dc.replace(a, seconds=float(spent[i])) for i, a in enumerate(answers)]


def tori_of_sweep(model, result, direction: str = "down", *, H2: int = 4, check: bool = True) -> TorusResult:
    """The tori at the points a periodic sweep marked quasi-periodic (a complex pair of
    Floquet multipliers outside the unit circle: finite ``secondary_frequency``), in the
    sweep's order along ``direction``, started from the sweep's stored (unstable) orbits.

    Parameters
    ----------
    model : LinkModel
        The model the sweep was made on (one mesh: its link model).
    result : LinkSweepResult or SweepResult
        The sweep (its mesh result holds the harmonics and the multipliers).
    direction : {"up", "down"}
        Which direction's points.
    H2 : int
        Harmonics of the secondary frequency [-].
    check : bool
        Also solve at (H + 4, H2 + 2) for the convergence estimate.

    Returns
    -------
    TorusResult
        One row per quasi-periodic point of that direction (none: an empty result).

    Raises
    ------
    ModelError
        When the sweep's harmonics are not of the mesh frequency itself (``base`` > 1).
    """
    mesh = result.result if hasattr(result, "links") else getattr(result, "mesh", result)
    if mesh.base != 1:
        raise ModelError("result", f"harmonics of ω/{mesh.base}: take the period-1 sweep (period=1)")
    keep = np.nonzero((mesh.direction == direction) & np.isfinite(mesh.secondary_frequency))[0]
    return torus_sweep(model, mesh.omega[keep], H=mesh.H, H2=H2, periodic=mesh.harmonics[keep], check=check)

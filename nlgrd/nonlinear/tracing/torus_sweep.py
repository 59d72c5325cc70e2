"""Quasi-periodic answers of a geared FE model: tori followed in speed.

Where a mesh-periodic orbit has lost stability to a complex pair of Floquet multipliers
μ = |μ| e^{±iθ} (a Neimark-Sacker bifurcation), the response is a torus with the mesh
frequency ω₁ and a secondary frequency ω₂ ≈ θ ω₁ / 2π. This module computes it by the
two-frequency harmonic balance of :mod:`nlgrd.nonlinear.hb.quasi_periodic` on the mesh
coordinate of the receptance-reduced model (:func:`nlgrd.nonlinear.models.geared.build_geared_model`),
the linear part entering through h(Ω) = wᵀ Z(Ω)⁻¹ w at each combination frequency Ω (Z of the
full FE model at the shaft speed of ω₁, with the mesh damping, without k_h: the matrix of
the periodic harmonic balance's direct receptance), and reports per point the mesh outputs
averaged over the torus and their change from (H₁, H₂) to (H₁ + 4, H₂ + 2).
"""

from __future__ import annotations

import dataclasses as dc
from dataclasses import dataclass

import numpy as np
import pandas as pd
import scipy.sparse.linalg as spla
from numpy.typing import NDArray

from nlgrd.errors import ModelError
from nlgrd.nonlinear.fourier.harmonics import real_to_complex
from nlgrd.nonlinear.hb import quasi_periodic as qp
from nlgrd.nonlinear.hb import torus_grid as tg
from nlgrd.nonlinear.hb.solvers import solve
from nlgrd.nonlinear.stability.floquet_mode import dominant_floquet_mode

#: Output names of a torus point, in the order of :attr:`TorusResult.outputs` (SI), with the
#: unit and factor of their table column.
TORUS_OUTPUTS = {
    "dte_mean": ("um", 1e6),
    "dte_rms": ("um", 1e6),
    "dte_max": ("um", 1e6),
    "dte_p2p": ("um", 1e6),
    "force_max": ("N", 1.0),
    "force_min": ("N", 1.0),
    "dslr": ("-", 1.0),
    "contact_loss_fraction": ("-", 1.0),
    "secondary_frequency": ("Hz", 1 / (2 * np.pi)),
}
#: The outputs whose change with (H₁, H₂) is the convergence estimate.
CHECKED = ("dte_rms", "force_max", "secondary_frequency")
#: Bearing forces below this fraction of the largest are rounding of the recovery (as the
#: sweep's :data:`nlgrd.nonlinear.models.geared` bearing columns).
BEARING_FLOOR = 1e-9
#: Largest relative speed step continued from the previous torus; beyond it the torus is
#: started afresh from the periodic orbit.
CONTINUATION_STEP = 0.02
#: Starts tried, as fractions of the periodic orbit's first-harmonic amplitude.
START_SIZES = (0.02, 0.1, 0.005, 0.3)


def geared_torus_model(model) -> qp.TorusModel:
    """The :class:`~nlgrd.nonlinear.hb.quasi_periodic.TorusModel` of a geared model.

    Parameters
    ----------
    model : GearedModel
        From :func:`nlgrd.nonlinear.models.geared.build_geared_model` (one mesh, period 1).

    Returns
    -------
    TorusModel
        κ(Ω) = (wᵀ Z(Ω)⁻¹ w)⁻¹ by a sparse LU of the full FE Z per frequency, at the speed of ω₁;
        the periodic κ_k and F_k of ``model.reduced``.

    Raises
    ------
    ModelError
        When the model is of period ν > 1.
    """
    rec = model.receptance
    if rec.period != 1:
        raise ModelError("period", f"the torus balance needs a period-1 model, got period {rec.period}")
    W = rec.W

    def kappa_at(freqs: NDArray, omega: float) -> NDArray:
        speed = rec.speed(omega)
        out = np.empty((len(freqs), W.shape[1], W.shape[1]), dtype=complex)
        for i, f in enumerate(freqs):
            Z = rec.model.dynamic_stiffness(float(f), speed).tocsc()
            out[i] = np.linalg.inv(W.T @ spla.splu(Z).solve(W.astype(complex)))
        return out

    return qp.TorusModel(kappa_at, model.reduced.kappa, model.reduced.force, model.reduced.nonlinearities)


def torus_outputs(sol: qp.TorusSolution, mesh, n_samples: tuple[int, int] = (256, 48)) -> NDArray:
    """The outputs :data:`TORUS_OUTPUTS` of a torus, on an ``n_samples`` grid of it (SI).

    DTE δ (mean, RMS of the alternating part, maximum, peak-to-peak), the mesh force
    W = k_h f(δ - e) + c_m (δ' - e') (extremes; DSLR = max W / W_0), the fraction of the torus
    without contact and ω₂ [rad/s]; averages over the torus are time averages of a
    quasi-periodic motion (ergodic on the torus when ω₂/ω₁ is irrational).

    Parameters
    ----------
    sol : TorusSolution
        A converged torus.
    mesh : BacklashMesh
        The mesh law (k_h, b, e, c_m, W_0).
    n_samples : tuple of int
        Samples along θ₁ and θ₂ [-].

    Returns
    -------
    ndarray (len(TORUS_OUTPUTS),)
        In the order of :data:`TORUS_OUTPUTS`; NaN when not converged.
    """
    if not sol.converged:
        return np.full(len(TORUS_OUTPUTS), np.nan)
    g = sol.grid
    fine = tg.TorusGrid(g.H1, g.H2, max(n_samples[0], 2 * g.H1 + 1), max(n_samples[1], 2 * g.H2 + 1))
    Y = sol.Y[:1]
    d = fine.samples(Y)[0]
    dd = fine.samples(Y, derivative=(sol.omega, sol.secondary))[0]
    th = fine.theta1
    e = mesh.offset(max(g.H1, (mesh.lste.size - 1) // 2))[0]
    from nlgrd.nonlinear.fourier.harmonics import differentiate, evaluate  # noqa: PLC0415

    ev, ed = evaluate(e, th), sol.omega * evaluate(differentiate(e), th)
    x = d - ev
    elastic = mesh.force_time(d[None, :], th)[0]
    W = elastic + mesh.damping * (dd - ed)
    W0 = float(mesh.static_load) if mesh.static_load else float(np.mean(W))
    return np.array(
        [
            np.mean(d),
            np.std(d),
            np.max(d),
            np.ptp(d),
            np.max(W),
            np.min(W),
            np.max(W) / W0,
            float(np.mean(np.abs(x) <= mesh.half_backlash)),
            sol.secondary,
        ]
    )


def torus_bearing_forces(model, sol: qp.TorusSolution, n_samples: tuple[int, int] = (256, 48)) -> NDArray:
    """The largest radial force of every bearing over a torus [N].

    All the forcing a mesh-reduced model has at k ≠ 0 acts along w (the mesh force and the
    LSTE's damping force), so each node follows δ: Q_k = (Z(Ω_k)⁻¹ w) h(Ω_k)⁻¹ Y_k at every
    combination frequency Ω_k; the mean Q_0 is the periodic recovery's
    (:meth:`~nlgrd.nonlinear.reduction.receptance.MeshReceptance.recover`). The force of bearing b on
    its node, -(K_b + i Ω_k C_b) q_k in (y, z), is sampled on the torus.

    Parameters
    ----------
    model : GearedModel
        The model solved.
    sol : TorusSolution
        A converged torus.
    n_samples : tuple of int
        Samples along θ₁ and θ₂ [-].

    Returns
    -------
    ndarray (n_bearings,)
        max |(F_y, F_z)| per bearing [N]; NaN when not converged.
    """
    nb = len(model.system.bearings)
    if not sol.converged:
        return np.full(nb, np.nan)
    return torus_bearing_outputs(model, sol, n_samples)["force_max"]


def _torus_bearing_harmonics(model, sol: qp.TorusSolution) -> tuple[NDArray, NDArray, NDArray]:
    """Each bearing node's (y, z) 2-D harmonics Q and its force's Fb (terms, 2 n_b), and
    the combination frequencies (terms,) [rad/s] (:func:`torus_bearing_forces`)."""
    system, rec = model.system, model.receptance
    g, w = sol.grid, sol.omega
    speed = rec.speed(w)
    Y = sol.Y[0]
    W = rec.W.astype(complex)
    dofs = model.bearing_dofs
    Q = np.zeros((g.n_terms, dofs.size), dtype=complex)
    H1 = g.H1
    F = np.asarray(model.reduced.force(w, H1), dtype=complex).reshape(H1 + 1, -1)
    kap = np.asarray(model.reduced.kappa(w, H1), dtype=complex).reshape(H1 + 1, -1)
    Yr = Y[: H1 + 1, None]
    Q[0] = rec.recover(w, Yr[:1], F[:1] - kap[:1] * Yr[:1], F[:1], dofs)[0]
    freqs = g.k1 * w + g.k2 * sol.secondary
    for i in range(1, g.n_terms):
        x = spla.splu(rec.model.dynamic_stiffness(float(freqs[i]), speed).tocsc()).solve(W)
        Q[i] = x[dofs] @ np.linalg.solve(rec.W.T @ x, [Y[i]])
    Fb = np.empty_like(Q)
    for j, b in enumerate(system.bearings):
        s_b = system.shafts[b.shaft].speed_ratio * speed
        q = Q[:, 2 * j : 2 * j + 2]
        Fb[:, 2 * j : 2 * j + 2] = -(q @ b.stiffness(s_b).T + (1j * freqs)[:, None] * (q @ b.damping(s_b).T))
    return Q, Fb, freqs


def torus_bearing_outputs(model, sol: qp.TorusSolution, n_samples: tuple[int, int] = (256, 48)) -> dict:
    """Every bearing's outputs over a torus, the quantities of a periodic sweep's bearing
    columns (:class:`~nlgrd.nonlinear.results.bearing_loads.BearingResponse`): radial
    displacement and force of its node sampled on the torus (their largest, the RMS of
    the alternating part, the magnitude of the mean) and the amplitude of the force's
    mesh harmonic (k₁ = 1, k₂ = 0; the larger of y and z). Q as
    :func:`torus_bearing_forces` recovers it.

    Parameters
    ----------
    model : GearedModel
        The model solved.
    sol : TorusSolution
        A converged torus.
    n_samples : tuple of int
        Samples along θ₁ and θ₂ [-].

    Returns
    -------
    dict of str to ndarray (n_bearings,)
        ``displacement_mean``, ``displacement_rms``, ``displacement_max`` [m],
        ``force_mean``, ``force_rms``, ``force_max``, ``force_amplitude`` [N].
    """
    nb = len(model.system.bearings)
    fields = ("displacement_mean", "displacement_rms", "displacement_max")
    fields += ("force_mean", "force_rms", "force_max", "force_amplitude")
    if not sol.converged or nb == 0:
        return {f: np.full(nb, np.nan) for f in fields}
    Q, Fb, _ = _torus_bearing_harmonics(model, sol)
    g = sol.grid
    fine = tg.TorusGrid(g.H1, g.H2, max(n_samples[0], 2 * g.H1 + 1), max(n_samples[1], 2 * g.H2 + 1))
    out = {f: np.empty(nb) for f in fields}
    for name, X in (("displacement", Q), ("force", Fb)):
        for j in range(nb):
            y, z = fine.samples(X[:, 2 * j : 2 * j + 2].T.copy())
            my, mz = float(np.mean(y)), float(np.mean(z))
            out[f"{name}_mean"][j] = np.hypot(my, mz)
            out[f"{name}_rms"][j] = np.sqrt(np.mean((y - my) ** 2 + (z - mz) ** 2))
            out[f"{name}_max"][j] = float(np.max(np.hypot(y, z)))
    out["force_amplitude"] = np.maximum(np.abs(Fb[1, 0::2]), np.abs(Fb[1, 1::2]))  # (k₁, k₂) = (1, 0)
    for f in fields:  # rounding of the recovery, not response (as the sweep's columns)
        v = out[f]
        v[np.abs(v) <= BEARING_FLOOR * np.max(np.abs(v))] = 0.0
    return out


@dataclass(frozen=True)
class TorusResult:
    """Tori of a geared model over speed, one row per speed.

    Attributes
    ----------
    omega : ndarray (n,)
        Mesh frequency ω₁ [rad/s].
    rpm : ndarray (n,)
        Pinion speed [rpm].
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
        :func:`torus_bearing_forces` per point [N].
    bearing_names : list of str
        The bearings' names, as the sweep's columns.
    solutions : list
        The :class:`~nlgrd.nonlinear.hb.quasi_periodic.TorusSolution` per point (None where
        not converged).
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
        """The table, units in the column names (`dte_rms [um]`, `force_max [N]`,
        `secondary_frequency [Hz]`, `torus_error [-]`: the largest convergence change).

        Returns
        -------
        pandas.DataFrame
        """
        cols = {
            "mesh_frequency [Hz]": self.omega / (2 * np.pi),
            "pinion_speed [rpm]": self.rpm,
            "response": np.where(self.converged, "quasi-periodic", ""),
            "converged": self.converged,
            "residual [-]": self.residual,
            "iterations": self.iterations,
            "H": self.H,
            "H2": self.H2,
        }
        for j, (name, (unit, factor)) in enumerate(TORUS_OUTPUTS.items()):
            cols[f"{name} [{unit}]"] = self.outputs[:, j] * factor
        for j, name in enumerate(CHECKED):
            cols[f"{name}_change [-]"] = self.change[:, j]
        cols["torus_error [-]"] = np.max(np.abs(self.change), axis=1)
        for j, name in enumerate(self.bearing_names):
            cols[f"{name} force_max [N]"] = self.bearing_force_max[:, j]
        cols["floquet_multiplier_abs [-]"] = np.abs(self.multiplier)
        cols["seconds [s]"] = self.seconds
        return pd.DataFrame(cols)


def _periodic(model, omega: float, H: int, start: NDArray | None) -> NDArray | None:
    """Real harmonics (1, 2H+1) of the periodic orbit at ``omega`` from ``start``."""
    sol = solve(model.reduced.at(omega, H), start)
    return sol.harmonics if sol.converged else None


def _start_torus(
    tm, model, omega: float, Zp: NDArray, grid, max_iter: int = 60, sizes: tuple | None = None
) -> tuple[qp.TorusSolution | None, complex]:
    """A torus from the periodic orbit and its critical Floquet mode, or None when the orbit
    has no complex pair outside the unit circle."""
    ss = model.reduced.linear_state_space(omega)
    mu = dominant_floquet_mode(ss, model.reduced.nonlinearities, Zp, omega).multiplier
    if abs(mu) <= 1 + 1e-6 or abs(mu.imag) <= 1e-6 * abs(mu):
        return None, mu
    w2 = qp.secondary_from_multiplier(mu, omega)
    Yp = real_to_complex(np.atleast_2d(Zp)[0])[None, :]
    shape = qp.critical_shape(tm, omega, Yp, w2, grid.H1)
    base = float(np.abs(Yp[0, 1:]).max())
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
) -> TorusResult:
    """Tori of a geared model at the given speeds, in their order (natural continuation).

    At the first speed (and after any speed without a torus) the periodic orbit is solved
    (from ``periodic`` when given, e.g. a sweep's stored harmonics of the points it marked
    quasi-periodic), its dominant Floquet multiplier computed, and where it is a complex
    pair outside the unit circle the torus started from the critical mode
    (:func:`~nlgrd.nonlinear.hb.quasi_periodic.critical_shape`) at ω₂ = |arg μ| ω₁ / 2π. Further
    speeds start from the previous torus, extrapolated linearly from the last two, with it as
    the phase reference (within ``CONTINUATION_STEP`` of the previous speed; farther, afresh).

    Parameters
    ----------
    model : GearedModel
        From :func:`nlgrd.nonlinear.models.geared.build_geared_model` (period 1, built for ``H`` + 4).
    omegas : array_like, optional
        Mesh frequencies [rad/s]; or
    rpm : array_like, optional
        pinion speeds [rpm].
    H : int
        Harmonics of the mesh frequency H₁ (the periodic sweep's H) [-].
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
    omegas = np.atleast_1d(np.asarray(model.mesh_frequency(rpm) if omegas is None else omegas, dtype=float))
    tm = geared_torus_model(model)
    grid = tg.TorusGrid(H, H2, *tg.default_grid(H, H2))
    fine = tg.TorusGrid(H + 4, H2 + 2, *tg.default_grid(H + 4, H2 + 2)) if check else None
    n = omegas.size
    out = np.full((n, len(TORUS_OUTPUTS)), np.nan)
    change = np.full((n, len(CHECKED)), np.nan)
    mult = np.full(n, np.nan + 0j)
    res, its, secs = np.full(n, np.nan), np.zeros(n, dtype=int), np.zeros(n)
    sols: list = [None] * n
    bears = model.system.bearings
    bear = np.full((n, len(bears)), np.nan)
    names = [b.name or f"bearing {j} (shaft {b.shaft}, node {b.node})" for j, b in enumerate(bears)]
    hist: list[tuple[float, qp.TorusSolution]] = []
    Zp = None
    idx = [list(TORUS_OUTPUTS).index(c) for c in CHECKED]
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
            Zp = _periodic(model, float(w), H, start)
            if Zp is not None:
                sol, mult[i] = _start_torus(tm, model, float(w), Zp, grid, max_iter, start_sizes)
        if sol is not None and sol.converged:
            sols[i] = sol
            hist = (hist + [(float(w), sol)])[-2:]
            out[i] = torus_outputs(sol, model.mesh)
            bear[i] = torus_bearing_forces(model, sol)
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
                    ob = torus_outputs(big, model.mesh)
                    change[i] = ob[idx] / out[i][idx] - 1
        else:
            hist = []
        secs[i] = time.perf_counter() - t0
        if progress is not None:
            progress(i + 1, n)
    return TorusResult(
        omegas,
        model.pinion_rpm(omegas),
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
    )


#: Raises of H₁ over the sweep's H tried until a torus's convergence estimate meets the
#: tolerance (each rung checked at H₁ + 4, H₂ + 2).
TORUS_LADDER = (0, 4, 8)
#: Largest H₁ of the ladder (the model is built for it + 4).
TORUS_MAX_H = 17
#: Newton iterations of a sweep's torus solve: Kubo's tori converge in 3-12 from the
#: critical mode or the previous torus (benchmarks/torus_kubo_reference*.csv); a start
#: that has not converged by then is abandoned (a chaotic band costs 60 a start otherwise).
ANSWER_MAX_ITER = 25
#: Relative residual of a sweep's torus solve: below the default 1e-8, so that the noise
#: its start carries (the Floquet mode's last bits) stays far below the digits written.
ANSWER_TOL = 1e-10
#: The starts a sweep's torus tries from the periodic orbit (the first two of
#: :data:`START_SIZES`; the first started every Kubo torus of the reference band).
ANSWER_START_SIZES = START_SIZES[:2]


def torus_back_contact(sol: qp.TorusSolution, mesh, n_samples: tuple[int, int] = (256, 48)) -> bool:
    """Whether the back flanks touch anywhere on a torus: δ - e below -b on the sampled
    torus (never for a one-sided stop, whose teeth have no back flank).

    Parameters
    ----------
    sol : TorusSolution
        A converged torus of the mesh coordinate.
    mesh : BacklashMesh
        The mesh law.
    n_samples : tuple of int
        Samples along θ₁ and θ₂ [-].

    Returns
    -------
    bool
    """
    from nlgrd.nonlinear.fourier.harmonics import evaluate  # noqa: PLC0415
    from nlgrd.nonlinear.laws.force_laws import ContactStop  # noqa: PLC0415

    if not sol.converged or isinstance(mesh, ContactStop):
        return False
    g = sol.grid
    fine = tg.TorusGrid(g.H1, g.H2, max(n_samples[0], 2 * g.H1 + 1), max(n_samples[1], 2 * g.H2 + 1))
    d = fine.samples(sol.Y[:1])[0]
    e = evaluate(mesh.offset(max(g.H1, (mesh.lste.size - 1) // 2))[0], fine.theta1)
    return bool(np.any(d - e < -mesh.half_backlash))


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
        :func:`torus_bearing_outputs`.
    error : float
        Its convergence estimate: the largest relative change of the :data:`CHECKED`
        outputs from (H₁, H₂) to (H₁ + 4, H₂ + 2) [-].
    H : int
        H₁, harmonics of the mesh frequency [-].
    H2 : int
        Harmonics of the secondary frequency [-].
    seconds : float
        Wall time of its rungs, checks included [s].
    """

    solution: qp.TorusSolution
    outputs: dict
    bearings: dict
    error: float
    H: int
    H2: int
    seconds: float


def converged_tori(
    model,
    omegas: NDArray,
    periodic: NDArray,
    *,
    H: int,
    rtol: float,
    H2: int = 4,
    progress=None,
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
    model : GearedModel
        Built for at least the top rung + 4 harmonics (period 1).
    omegas : ndarray (n,)
        Mesh frequencies, in the sweep's order [rad/s].
    periodic : ndarray (n, 1, 2H+1)
        The (unstable) periodic orbits there, starts of the periodic solve [m].
    H : int
        The sweep's H [-].
    rtol : float
        The sweep's tolerance on its outputs [-].
    H2 : int
        Harmonics of the secondary frequency [-].
    progress : callable (done, total), optional
        Called after each rung.

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
    rungs = [H + r for r in TORUS_LADDER if H + r <= max(H, TORUS_MAX_H)]
    for k, Hr in enumerate(rungs):
        if not pending.size:
            break
        starts = np.zeros((pending.size, 1, 2 * Hr + 1))
        z = np.asarray(periodic, dtype=float)[pending].reshape(pending.size, -1)
        m = min(z.shape[1], 2 * Hr + 1)
        starts[:, 0, :m] = z[:, :m]
        res = torus_sweep(
            model,
            np.asarray(omegas, dtype=float)[pending],
            H=Hr,
            H2=H2,
            periodic=starts,
            tol=ANSWER_TOL,
            max_iter=ANSWER_MAX_ITER,
            start_sizes=ANSWER_START_SIZES,
        )
        spent[pending] += res.seconds
        err = np.max(np.abs(res.change), axis=1)  # NaN: the check did not converge
        for row, i in enumerate(pending):
            sol = res.solutions[row]
            if sol is not None and np.isfinite(err[row]) and err[row] <= rtol:
                t0 = time.perf_counter()
                out = dict(zip(TORUS_OUTPUTS, res.outputs[row], strict=True))
                out["back_contact"] = torus_back_contact(sol, model.mesh)
                bearings = torus_bearing_outputs(model, sol)
                spent[i] += time.perf_counter() - t0
                answers[i] = TorusAnswer(sol, out, bearings, float(err[row]), Hr, H2, 0.0)
        # only a torus found but short of the tolerance climbs: one not found at H₁ (no
        # torus near the orbit, e.g. a chaotic band) is not sought again at a higher H₁
        climb = [i for row, i in enumerate(pending) if answers[i] is None and np.isfinite(err[row])]
        pending = np.array(climb, dtype=int)
        if progress is not None:
            progress(k + 1, len(rungs))
    return [None if a is None else dc.replace(a, seconds=float(spent[i])) for i, a in enumerate(answers)]


def tori_of_sweep(model, result, direction: str = "down", *, H2: int = 4, check: bool = True) -> TorusResult:
    """The tori at the points a periodic sweep marked quasi-periodic (a complex pair of
    Floquet multipliers outside the unit circle: finite ``secondary_frequency``), in the
    sweep's order along ``direction``, started from the sweep's stored (unstable) orbits.

    Parameters
    ----------
    model : GearedModel
        The model the sweep was made on.
    result : GearedSweepResult or SweepResult
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
    mesh = getattr(result, "mesh", result)
    if mesh.base != 1:
        raise ModelError("result", f"harmonics of ω/{mesh.base}: take the period-1 sweep (period=1)")
    keep = np.nonzero((mesh.direction == direction) & np.isfinite(mesh.secondary_frequency))[0]
    return torus_sweep(model, mesh.omega[keep], H=mesh.H, H2=H2, periodic=mesh.harmonics[keep], check=check)

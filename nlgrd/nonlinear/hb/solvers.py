"""Solvers of the harmonic-balance equations R(z) = 0 of a :class:`ReducedProblem`.

Damped Newton (Armijo backtracking on ||R||²) with scipy's MINPACK ``hybr`` as the
fallback, or the paper's quasi-linear receptance iteration (Maliha, Doğruer & Özgüven
2004, Eq. 35-37; ``method="quasi-linear"``); :func:`solve` chooses and reports.
"""

from __future__ import annotations

import numpy as np
import scipy.optimize as so
from numpy.typing import ArrayLike, NDArray

from nlgrd.errors import ModelError
from nlgrd.nonlinear.fourier.harmonics import complex_to_real, real_to_complex
from nlgrd.nonlinear.hb.harmonic_balance import HarmonicSolution, ReducedProblem

#: Damped Newton gives up after this many failed line searches in a row, or when ||R||
#: fell by less than 10 % over the last ``STALL_WINDOW`` iterations.
STALL_LIMIT = 8
STALL_WINDOW = 25


def _newton(
    problem: ReducedProblem,
    z: NDArray,
    tol: float,
    max_iter: int,
    stall: bool = False,
    max_step: float | None = None,
) -> tuple[NDArray, float, int, str]:
    """Damped Newton with Armijo backtracking on ||R||²; returns (z, relres, iterations, msg).

    With ``stall``, gives up early when the line search has failed (no sufficient
    decrease even at the smallest step) ``STALL_LIMIT`` times in a row, or when ||R||
    fell by less than 10 % over ``STALL_WINDOW`` iterations: Newton is then stuck near a
    minimum of ||R|| that is not a root, as when started from a branch that has folded
    away. Without it, slow progress at grazing points is given all ``max_iter``.
    ``max_step`` caps each Newton direction's largest component (a trust region in the
    unit of z).
    """
    R, J, scale = problem.residual_jacobian(z)
    rel = np.max(np.abs(R)) / scale
    nrm = np.linalg.norm(R)
    it = 0
    stalled = 0
    history = [nrm]
    msg = "converged"
    while rel > tol:
        if it >= max_iter:
            msg = f"no convergence in {max_iter} Newton iterations"
            break
        if stall and stalled >= STALL_LIMIT:
            msg = f"Newton stalled ({STALL_LIMIT} failed line searches in a row)"
            break
        it += 1
        try:
            dz = -np.linalg.solve(J, R)
        except np.linalg.LinAlgError:
            dz = -np.linalg.lstsq(J, R, rcond=None)[0]
        longest = float(np.max(np.abs(dz), initial=0.0))
        if max_step is not None and longest > max_step:
            dz *= max_step / longest
        if not np.all(np.isfinite(dz)):
            msg = "singular Jacobian"
            break
        step = 1.0
        while True:
            zt = z + step * dz
            try:  # a step so long that the iterate overflows is a failed step
                Rt, Jt, st = problem.residual_jacobian(zt)
                nt = np.linalg.norm(Rt)
            except (np.linalg.LinAlgError, FloatingPointError):
                Rt, Jt, st, nt = R, J, scale, np.inf
            if not np.isfinite(nt) and step < 1 / 64:
                break
            if nt <= (1 - 1e-4 * step) * nrm or step < 1 / 64:
                break
            step /= 2
        if not np.isfinite(nt):
            msg = "the Newton step overflows"
            break
        stalled = stalled + 1 if nt > (1 - 1e-4 * step) * nrm else 0
        z, R, J, scale, nrm = zt, Rt, Jt, st, nt
        history.append(nrm)
        if stall and len(history) > STALL_WINDOW and nrm > 0.9 * history[-1 - STALL_WINDOW]:
            msg = f"Newton stalled (||R|| fell by less than 10 % in {STALL_WINDOW} iterations)"
            rel = np.max(np.abs(R)) / scale
            break
        rel = np.max(np.abs(R)) / scale
    return z, rel, it, msg


def _hybr(problem: ReducedProblem, z: NDArray, tol: float, max_iter: int) -> tuple[NDArray, float, int, str]:
    """MINPACK hybrid Powell method with the analytic Jacobian (scaled unknowns)."""
    zs = np.maximum(np.abs(z), 1e-3 * np.max(np.abs(z)) + 1e-300)
    fs = problem.force_scale(z)

    def fun(u):
        R, J, _ = problem.residual_jacobian(u * zs)
        return R / fs, J * zs[None, :] / fs

    sol = so.root(
        fun, z / zs, jac=True, method="hybr", options={"maxfev": 50 * max(max_iter, 4), "xtol": 1e-13}
    )
    zn = sol.x * zs
    R = problem.residual(zn)
    return zn, float(np.max(np.abs(R)) / problem.force_scale(zn)), int(sol.nfev), f"hybr: {sol.message}"


def _quasi_linear(
    problem: ReducedProblem, z: NDArray, tol: float, max_iter: int, relaxation: float
) -> tuple[NDArray, float, int, str]:
    """The paper's quasi-linear receptance iteration (Maliha et al. 2004, Eq. 24-25, 32).

    Each nonlinear force harmonic is written G_k = ν_k (Y_k - O_k) with the describing
    gain ν_k = G_k / (Y_k - O_k) of the current iterate (O: the excitation offset inside
    the force law, e.g. the LSTE), and the now linear harmonic equations
    (κ_k + B_k N_k) Y_k = F_k + B_k N_k O_k are solved; relaxation blends old and new.
    A harmonic whose secant gain would exceed twice the largest tangent gain (a harmonic
    absent or nearly absent from Y - O, generated by the others rather than by itself)
    gets the tangent gain instead and the remaining force G_k - ν_k (Y_k - O_k) on the
    right-hand side; with the pure secant gain such harmonics never appear or stall
    the iteration (observed: residual stuck at 2 % with contact loss).
    The plain iteration (relaxation 1) diverges whenever the secant gain of the mean is
    too far from its tangent (e.g. b > W_0/k_h: the map of the mean has slope
    -b k_h/W_0); the relaxation factor is therefore halved whenever the residual grows
    (a negative ``relaxation`` fixes it at |relaxation|).
    """
    H, n = problem.H, problem.n_coords
    nh = 2 * H + 1
    B = np.broadcast_to(np.eye(n), (H + 1, n, n)) if problem.nl_gain is None else problem.nl_gain
    msg = f"no convergence in {max_iter} quasi-linear iterations"
    adaptive = relaxation > 0
    relaxation = abs(relaxation)
    r = relaxation
    rel = np.max(np.abs(problem.residual(z))) / problem.force_scale(z)
    it = 0
    while it < max_iter:
        it += 1
        Z = z.reshape(n, nh)
        N = np.zeros((H + 1, n, n), dtype=complex)
        O = np.zeros((H + 1, n), dtype=complex)
        Rf = np.zeros((H + 1, n), dtype=complex)
        for nl in problem.nonlinearities:
            if len(nl.coords) != 1:
                raise ModelError("method", "quasi-linear iteration needs single-coordinate nonlinearities")
            c = nl.coords[0]
            g, jg = nl.harmonics(Z[[c]], jacobian=True)
            off = nl.offset(H)[0]
            U = real_to_complex(Z[c] - off)
            Gc = real_to_complex(g[0])
            Jdiag = np.concatenate([[jg[0, 0]], 0.5 * (np.diag(jg)[1::2] + np.diag(jg)[2::2])])
            big = np.abs(U) * (np.max(np.abs(Jdiag)) + 1e-300) > 0.5 * np.abs(Gc)
            nu = np.where(big, Gc / np.where(big, U, 1), Jdiag)
            N[:, c, c] += nu
            O[:, c] = real_to_complex(off)
            Rf[:, c] += Gc - nu * U  # zero where the secant gain is used
        BN = B @ N
        rhs = problem.force + np.einsum("kij,kj->ki", BN, O) - np.einsum("kij,kj->ki", B, Rf)
        try:
            Y = np.linalg.solve(problem.kappa + BN, rhs[..., None])[..., 0]
        except np.linalg.LinAlgError:  # e.g. full separation: zero gain and κ_0 = 0
            Y = np.array(
                [np.linalg.lstsq(a, r, rcond=None)[0] for a, r in zip(problem.kappa + BN, rhs, strict=True)]
            )
        znew = complex_to_real(Y.T).reshape(-1)
        # adaptive under-relaxation: halve when the residual grows, regrow slowly otherwise
        while True:
            zc = (1 - r) * z + r * znew
            rel_c = np.max(np.abs(problem.residual(zc))) / problem.force_scale(zc)
            if rel_c < rel or r <= 1 / 256 or not adaptive:
                break
            r /= 2
        z, rel = zc, rel_c
        r = min(relaxation, 1.25 * r)
        if rel <= tol:
            msg = "converged"
            break
    rel = np.max(np.abs(problem.residual(z))) / problem.force_scale(z)
    return z, float(rel), it, msg


def solve(
    problem: ReducedProblem,
    z0: ArrayLike | None = None,
    *,
    method: str = "newton",
    tol: float = 1e-10,
    max_iter: int = 50,
    fallback: bool = True,
    relaxation: float = 1.0,
    stall: bool = False,
    max_step: float | None = None,
) -> HarmonicSolution:
    """Solve the reduced harmonic-balance problem at one frequency.

    Parameters
    ----------
    problem : ReducedProblem
        The problem at one frequency.
    z0 : array_like, optional
        Start: real harmonics [y_0, a_1, b_1, ...] of the nonlinear coordinates (δ [m] for a
        mesh), (n_nl, 2H+1) or flat; default :meth:`ReducedProblem.linear_solution`.
        Harmonics beyond the problem's H are dropped, missing ones set to zero.
    method : {"newton", "quasi-linear", "hybr"}
        Damped Newton with analytic Jacobian; the paper's quasi-linear receptance
        iteration; or MINPACK hybr directly.
    tol : float
        Convergence: max|R| <= tol · max(|L z|, |B G|, |F|) [-].
    max_iter : int
        Iteration limit of the chosen method.
    fallback : bool
        If Newton (or the quasi-linear iteration) fails, retry with hybr from the start.
    relaxation : float
        Largest under-relaxation of the quasi-linear iteration (1 = the paper's plain
        iteration), reduced adaptively when the residual grows; negative: fixed at |value|.
    stall : bool
        Let Newton give up early when it stalls (see ``_newton``): for sweeps that have a
        better move than grinding on, such as following the curve through a fold.
    max_step : float, optional
        Newton only: the largest change of any harmonic per iteration (unit of z, [m]),
        e.g. a fraction of a law's gap (:func:`~nlgrd.nonlinear.tracing.orbit_search.search_orbits`);
        None: the full Newton step.

    Returns
    -------
    HarmonicSolution
        ``converged`` False (and harmonics NaN) when the tolerance was not met.

    Raises
    ------
    ModelError
        When ``method`` is unknown, or is "quasi-linear" with a nonlinearity acting on more
        than one coordinate.
    """
    n, nh = problem.n_coords, 2 * problem.H + 1
    if z0 is None:
        z = problem.linear_solution()
    else:
        z0 = np.atleast_2d(np.asarray(z0, dtype=float))
        if z0.size == problem.size and z0.shape != (n, nh):
            z0 = z0.reshape(n, nh)
        z = np.zeros((n, nh))
        m = min(nh, z0.shape[1])
        z[:, :m] = z0[:, :m]
        z = z.reshape(-1)
    if not np.all(np.isfinite(z)):
        z = problem.linear_solution()
    if method == "newton":
        zr, rel, it, msg = _newton(problem, z, tol, max_iter, stall, max_step)
    elif method == "quasi-linear":
        zr, rel, it, msg = _quasi_linear(problem, z, tol, max_iter, relaxation)
    elif method == "hybr":
        zr, rel, it, msg = _hybr(problem, z, tol, max_iter)
    else:
        raise ModelError("method", f"'newton', 'quasi-linear' or 'hybr', got {method!r}")
    used = method
    if (not rel <= tol) and fallback and method != "hybr":
        zh, relh, ith, msgh = _hybr(problem, z, tol, max_iter)
        it += ith
        if relh < rel or not np.isfinite(rel):
            zr, rel, msg, used = zh, relh, msgh, "hybr"
        if rel <= tol:
            zr, rel2, it2, _ = _newton(problem, zr, tol, 5)  # polish to Newton accuracy
            rel, it = min(rel, rel2), it + it2
    converged = bool(rel <= tol and np.all(np.isfinite(zr)))
    harm = zr.reshape(n, nh) if converged else np.full((n, nh), np.nan)
    return HarmonicSolution(problem.omega, harm, converged, float(rel), int(it), used, zr.reshape(n, nh), msg)


# --------------------------------------------------------------------------------------
# Frequency-dependent model
# --------------------------------------------------------------------------------------

"""The HHT-α step and the static start shared by nlgrd's time integrators.

Method: HHT-α (Hilber, Hughes & Taylor 1977, Earthq. Eng. Struct. Dyn. 5:283), implicit,
unconditionally stable and second order for -1/3 <= α <= 0, with γ = (1 - 2α)/2,
β = (1 - α)²/4. Why: an FE rotor is stiff (bearing and bending modes far above the mesh
frequency), so an explicit scheme would need tiny steps; α < 0 damps the spurious
high-frequency FE modes excited at every contact change (the trapezoidal rule, α = 0,
would let them ring forever and spoil the periodicity test), while the dissipation at the
mesh frequency is O((ωΔt)³). With a fixed step Δt = T / steps_per_period the effective
stiffness K_eff = M/(βΔt²) + (1+α)(γ/(βΔt) D + K) is factorised once (sparse LU,
:func:`hht_step`); the integrator that steps it is
:class:`nlgrd.timedomain.links.LinkIntegrator`.

A single-mesh FE integration starts from the static solution with the mesh at k_h in
drive-side contact, (K + k_h w wᵀ) q_s = F0 + k_h w (e_0 + b) (:func:`static_solution`;
a free torsional rigid-body mode of the whole train is left at zero; F0 must be
self-equilibrated).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from numpy.typing import ArrayLike, NDArray

from nlgrd.errors import ModelError
from nlgrd.nonlinear.laws.force_laws import BacklashMesh
from nlgrd.rotor.assembly import mesh_matrix
from nlgrd.rotor.rigid_body import check_balanced, rigid_body_modes


def _csc(a) -> sp.csc_matrix:
    return sp.csc_matrix(a) if not sp.issparse(a) else a.tocsc()


@dataclass(frozen=True)
class HHTStep:
    """The fixed matrices of an HHT-α step of size dt (Hilber, Hughes & Taylor 1977).

    With β = (1 - α)²/4, γ = 1/2 - α, the step solves K_eff q_{n+1} = A [q_n; v_n; a_n] +
    (forces), K_eff = a1 M + (1 + α)(b1 D + K), and updates a_{n+1} = a1 (q_{n+1} - q_n) -
    a2 v_n - a3 a_n, v_{n+1} = b1 (q_{n+1} - q_n) + b2 v_n + b3 a_n.

    Attributes
    ----------
    gamma : float
        γ [-].
    a1, a2, a3, b1, b2, b3 : float
        The Newmark coefficients above [1/s², 1/s, -, 1/s, -, s].
    ap : float
        1 + α [-].
    lu : scipy.sparse.linalg.SuperLU
        The factors of K_eff.
    A_all : scipy.sparse.csr_matrix (N, 3N)
        A, acting on the state [q_n; v_n; a_n].
    """

    gamma: float
    a1: float
    a2: float
    a3: float
    b1: float
    b2: float
    b3: float
    ap: float
    lu: object
    A_all: sp.csr_matrix


def hht_step(M, D, K, dt: float, alpha: float) -> HHTStep:
    """The matrices of an HHT-α step (shared by every time integrator of nlgrd).

    Parameters
    ----------
    M, D, K : sparse (N, N)
        Mass [kg], velocity [N s/m] and stiffness [N/m] matrices.
    dt : float
        Time step [s].
    alpha : float
        HHT-α parameter in [-1/3, 0] [-].

    Returns
    -------
    HHTStep
    """
    gamma, beta = 0.5 - alpha, (1 - alpha) ** 2 / 4
    a1, a2, a3 = 1 / (beta * dt * dt), 1 / (beta * dt), 1 / (2 * beta) - 1
    b1, b2, b3 = gamma / (beta * dt), 1 - gamma / beta, dt * (1 - gamma / (2 * beta))
    ap = 1 + alpha
    lu = spla.splu((a1 * M + ap * (b1 * D + K)).tocsc())
    A_all = sp.hstack(
        [a1 * M + ap * b1 * D + alpha * K, a2 * M - ap * b2 * D + alpha * D, a3 * M - ap * b3 * D]
    ).tocsr()
    return HHTStep(gamma, a1, a2, a3, b1, b2, b3, ap, lu, A_all)


def static_solution(K, projection: ArrayLike, mesh: BacklashMesh, static_force: ArrayLike, M=None) -> NDArray:
    """Static deflection with the mesh at k_h in drive-side contact (minimum norm).

    Solves (K + k_h w wᵀ) q = F0 + k_h w (e_0 + b) by a sparse LU of the system bordered
    with its null space R (the rigid-body modes of (K + k_h w wᵀ, M) from
    :func:`nlgrd.rotor.rigid_body.rigid_body_modes`; M = I when not given) and the constraint
    Rᵀ q = 0: the minimum-norm solution. Raises ModelError when F0 has a net component
    on a rigid-body mode or the residual is not small.

    Parameters
    ----------
    K : sparse or dense (N, N)
        Stiffness without the mesh [N/m].
    projection : array_like (N,)
        The projection w onto the line of action, δ = wᵀ q [-].
    mesh : BacklashMesh
        k_h, b and the LSTE mean e_0.
    static_force : array_like (N,)
        F0, self-equilibrated static loads [N, N m].
    M : sparse or dense (N, N), optional
        Mass [kg], the metric of the rigid-body modes (identity when None).

    Returns
    -------
    ndarray (N,)
        The static displacements q [m, rad].
    """
    w = np.asarray(projection, dtype=float).reshape(-1)
    F0 = np.asarray(static_force, dtype=float).reshape(-1)
    n = w.size
    Ks = (_csc(K) + mesh_matrix(w, [mesh.stiffness])).tocsc()
    rhs = F0 + mesh.stiffness * w * (mesh.lste[0] + mesh.half_backlash)
    Mm = sp.identity(n, format="csc") if M is None else _csc(M)
    R = rigid_body_modes(Ks, Mm)
    check_balanced(R, F0, "static_force", "the static forces")
    if R.shape[1]:
        Rq = sp.csc_matrix(np.linalg.qr(R)[0])
        A = sp.bmat([[Ks, Rq], [Rq.T, None]], format="csc")
        q = spla.splu(A).solve(np.concatenate([rhs, np.zeros(R.shape[1])]))[:n]
    else:
        q = spla.splu(Ks).solve(rhs)
    res = np.linalg.norm(Ks @ q - rhs)
    if res > 1e-8 * (np.linalg.norm(rhs) + 1e-300):
        raise ModelError("static_force", f"not self-equilibrated: static residual {res:.3e} N")
    return q

"""Fourth-order Magnus steps in the interaction picture of a constant state matrix, for a
tangent that varies only through the projection W onto the nonlinear coordinates (the
modified Magnus method, Iserles 2002, BIT 42:561; the fourth-order term with two Gauss
points of Iserles & Nørsett 1999, Phil. Trans. R. Soc. A 357:983).

:func:`interaction_piece` is one piece of :func:`nlgrd.nonlinear.stability.floquet._magnus_monodromy`:
two full exponentials per piece and step count, a product per step, and
:func:`thin_steps` replaces those products by rank-2 n_nl updates where that is well
conditioned.
"""

from __future__ import annotations

import numpy as np
import scipy.linalg as sla
from numpy.typing import NDArray

from nlgrd.nonlinear.reduction.linear_algebra import expm

#: The steps of a piece are multiplied as rank-2 n_nl updates (:func:`thin_steps`) while
#: E^{-j} L and Rᵀ E^j grow by at most this factor together (rounding ~1e-16 times it).
THIN_GROWTH = 1e4

#: e^{-A₀ s} may amplify the input U₀ by at most this within a step (1/√eps): beyond it a
#: stiff decaying mode (|Re λ| h ≫ 1) makes the interaction picture's B̃ overflow and its
#: Magnus series diverge; :func:`plain_steps` takes the piece.
INTERACTION_GROWTH = 1e8


def interaction_piece(
    A0: NDArray, U0: NDArray, V0t: NDArray, Kbar: NDArray, Kt: NDArray, dt: float, memo: dict
) -> NDArray[np.float64]:
    """The propagator of one piece of m Magnus steps of x' = (A₀ + U₀ (K̄ - K_t(t)) V₀ᵀ) x.

    A step is e^{A₀ h} exp(Ω̃), Ω̃ the fourth-order Magnus term of B̃(s) = e^{-A₀ s} B(s)
    e^{A₀ s}, B = U₀ C V₀ᵀ, C = K̄ - K_t: Ω̃ = h/2 (B̃₁ + B̃₂) + √3 h²/12 [B̃₂, B̃₁] =
    L S Rᵀ with L = [U₁ U₂], R = [V₁ V₂], U_g = e^{-A₀ s_g} U₀, V_gᵀ = V₀ᵀ e^{A₀ s_g} (the
    same for every step: only C changes) and S = [[h/2 C₁, -c C₁ G₁₂ C₂], [c C₂ G₂₁ C₁,
    h/2 C₂]] (c = √3 h²/12, G = Rᵀ L). So exp(Ω̃) = I + L φ₁(S G) S Rᵀ exactly (φ₁(X) =
    (e^X - I) X⁻¹, from the exponential of [[X, I], [0, 0]]): one product with e^{A₀ h}
    per step instead of a full exponential. Any constant A₀ is exact in this picture; the
    mean tangent K̄ keeps C small. e^{A₀ s_g} are computed for half the step and squared,
    and kept in ``memo`` for twice the step count.

    Parameters
    ----------
    A0 : ndarray (2N, 2N)
        The constant state matrix (scaled state) [1/s].
    U0 : ndarray (2N, n)
        Input of the tangent's variation to the state (M⁻¹W in the velocity rows) [1/kg].
    V0t : ndarray (n, 2N)
        The nonlinear coordinates from the state (Wᵀ/w_s on the scaled displacements) [s].
    Kbar : ndarray (n, n)
        The tangent in ``A0`` [N/m].
    Kt : ndarray (2m, n, n)
        The tangent at the first Gauss point of every step, then at the second [N/m].
    dt : float
        Step length [s].
    memo : dict
        This piece's store across step counts (filled here).

    Returns
    -------
    ndarray (2N, 2N)
        The product of the m steps (the first acts first).
    """
    n = Kt.shape[1]
    m = Kt.shape[0] // 2
    g = np.sqrt(3.0) / 6.0
    C1, C2 = Kbar - Kt[:m], Kbar - Kt[m:]
    if "decay" not in memo:  # A₀'s fastest decay rate [1/s], bounded by ‖A₀‖₁ (≥ its spectral radius)
        bound = float(np.linalg.norm(A0, 1))
        fine = bound * dt * (0.5 + g) <= np.log(INTERACTION_GROWTH)  # later step counts: dt halves
        memo["decay"] = bound if fine else max(0.0, float(np.max(-np.linalg.eigvals(A0).real)))
    if memo["decay"] * dt * (0.5 + g) > np.log(INTERACTION_GROWTH):
        return plain_steps(A0, U0, V0t, C1, C2, dt)
    Fs = memo.pop(m, None)
    if Fs is None:  # e^{A₀ s_g} of 2m steps, then squared
        memo[2 * m] = [expm(A0 * (0.5 * sg)) for sg in (dt * (0.5 - g), dt * (0.5 + g))]
        Fs = [F @ F for F in memo[2 * m]]
    E = Fs[1] @ Fs[0]  # e^{A₀ h}: s₁ + s₂ = h
    L = np.hstack([np.linalg.solve(F, U0) for F in Fs])
    Rt = np.vstack([V0t @ F for F in Fs])
    G = Rt @ L
    c = np.sqrt(3.0) / 12.0 * dt * dt
    S = np.zeros((m, 2 * n, 2 * n))
    S[:, :n, :n], S[:, n:, n:] = 0.5 * dt * C1, 0.5 * dt * C2
    S[:, :n, n:] = -c * (C1 @ G[:n, n:] @ C2)
    S[:, n:, :n] = c * (C2 @ G[n:, :n] @ C1)
    aug = np.zeros((m, 4 * n, 4 * n))
    aug[:, : 2 * n, : 2 * n] = S @ G
    aug[:, : 2 * n, 2 * n :] = np.eye(2 * n)
    P = sla.expm(aug)[:, : 2 * n, 2 * n :] @ S  # φ₁(S G) S
    if "Em" not in memo:  # e^{A₀ m h}: the piece's length, the same at every step count
        memo["Em"] = np.linalg.matrix_power(E, m)  # by squarings, as expm's last stage
    X = thin_steps(E, L, Rt, P)
    if X is not None:
        return memo["Em"] @ X
    EL = E @ L
    Phi = np.eye(A0.shape[0])
    for j in range(m):
        Phi = E @ Phi + EL @ (P[j] @ (Rt @ Phi))
    return Phi


def thin_steps(E: NDArray, L: NDArray, Rt: NDArray, P: NDArray) -> NDArray[np.float64] | None:
    """X with E(I + L P_m Rᵀ) ⋯ E(I + L P_1 Rᵀ) = E^m X, by rank-k updates only.

    X = (I + L_m P_m R_mᵀ) ⋯ (I + L_1 P_1 R_1ᵀ), L_j = E^{1-j} L, R_jᵀ = Rᵀ E^{j-1}, since
    E(I + L P Rᵀ) E^{j-1} = E^j (I + L_j P R_jᵀ): O(N² k) per step instead of a full
    product. None when ‖L_j‖₁ ‖R_jᵀ‖∞ grows beyond ``THIN_GROWTH`` times ‖L‖₁ ‖Rᵀ‖∞
    (E^{-j} amplifies the decaying modes; the rounding of the updates grows with it).

    Parameters
    ----------
    E : ndarray (N, N)
        The step's constant propagator e^{A₀ h} [-].
    L : ndarray (N, k)
        Left factor of the updates.
    Rt : ndarray (k, N)
        Right factor of the updates.
    P : ndarray (m, k, k)
        The updates' cores, the first step first.

    Returns
    -------
    ndarray (N, N) or None
        X, or None when the updates would be ill-conditioned.
    """
    m = P.shape[0]
    Einv = np.linalg.inv(E)  # E⁻¹ once: a product per step (the growth check bounds its rounding)
    scale = np.abs(L).sum(axis=0).max() * np.abs(Rt).sum(axis=1).max()  # ‖L‖₁ ‖Rᵀ‖∞
    Lj, Rj = L, Rt
    X = np.eye(E.shape[0])
    for j in range(m):
        X += Lj @ (P[j] @ (Rj @ X))
        if j + 1 < m:
            Lj, Rj = Einv @ Lj, Rj @ E
            if np.abs(Lj).sum(axis=0).max() * np.abs(Rj).sum(axis=1).max() > THIN_GROWTH * scale:
                return None
    return X


def plain_steps(A0: NDArray, U0: NDArray, V0t: NDArray, C1: NDArray, C2: NDArray, dt: float) -> NDArray:
    """The propagator of m fourth-order Magnus steps of x' = (A₀ + U₀ C(t) V₀ᵀ) x without
    the interaction picture: exp(h/2 (A₁ + A₂) + √3 h²/12 [A₂, A₁]) per step, A_g = A₀ + U₀
    C_g V₀ᵀ, each exponential by scaling and squaring (a stiff decaying mode of A₀ needs
    no inverse exponential here).

    Parameters
    ----------
    A0 : ndarray (2N, 2N)
        The constant state matrix [1/s].
    U0 : ndarray (2N, n)
        Input of the tangent's variation to the state [1/kg].
    V0t : ndarray (n, 2N)
        The nonlinear coordinates from the state [s].
    C1, C2 : ndarray (m, n, n)
        K̄ - K_t at the first and second Gauss point of every step [N/m].
    dt : float
        Step length [s].

    Returns
    -------
    ndarray (2N, 2N)
        The product of the m steps (the first acts first).
    """
    c = np.sqrt(3.0) / 12.0 * dt * dt
    Phi = np.eye(A0.shape[0])
    for j in range(C1.shape[0]):
        A1, A2 = A0 + U0 @ C1[j] @ V0t, A0 + U0 @ C2[j] @ V0t
        Phi = expm(0.5 * dt * (A1 + A2) + c * (A2 @ A1 - A1 @ A2)) @ Phi
    return Phi


def set_distance(a: NDArray, b: NDArray) -> float:
    """Hausdorff distance of two sets of multipliers (inf when one is empty): the
    step-doubling comparison of two Magnus products' leading multipliers.

    Parameters
    ----------
    a, b : ndarray of complex
        The two sets [-].

    Returns
    -------
    float
    """
    if a.size == 0 or b.size == 0:
        return float("inf")
    d = np.abs(a[:, None] - b[None, :])
    return float(max(d.min(axis=1).max(), d.min(axis=0).max()))

"""One period of the HHT-α recurrence as an affine map, so that the step-by-step work of a
time integration is done on the few link coordinates only.

Between the link forces, an HHT-α step (:func:`nlgrd.timedomain.integrator.hht_step`) is
linear: with the extended state s = (q, q', q'', g_prev) (g_prev the link forces of the
previous step, which enter the α-weighted right-hand side),

    s_{n+1} = T s_n + B g_n + f_n,    y_lin,n = C s_n + φ_n,

where y_lin,n is the link coordinate the step would reach with g_n = 0 and g_n the link
forces solving y_n = y_lin,n - (1 + α) S g(y_n, θ_{n+1}). Over one period from s_0,

    y_lin,n = C Tⁿ s_0 + Σ_{m<n} C T^{n-1-m} B g_m + ψ_n,
    s_ns = T^ns s_0 + Σ_m T^{ns-1-m} B g_m + r_ns,

so the matrices C Tⁿ, the kernel C T^k B, T^ns and T^k B are computed once per frequency
and each step is the convolution sum and the links' own equation (d unknowns) instead of
a sparse solve of all N DOFs. The recurrence is the same; only the order of the floating
point operations differs (tests/test_time_domain_period_map.py compares the two).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numpy.typing import NDArray

#: Above this extended state dimension 3N + d the dense period map costs more than stepping.
MAX_STATE = 1500


class PeriodMap:
    """The affine map of one period of fixed HHT-α steps, for one frequency.

    Parameters
    ----------
    step : HHTStep
        The step matrices (:func:`nlgrd.timedomain.integrator.hht_step`).
    alpha : float
        HHT-α parameter [-].
    P : ndarray (N, d)
        Link directions: y = Pᵀ q [-].
    loads : ndarray (ns, N)
        The load term of step j's right-hand side (its forcing at steps j and j + 1,
        weighted 1 + α and -α) [N].
    """

    def __init__(self, step, alpha: float, P: NDArray, loads: NDArray):
        P = np.asarray(P, dtype=float)
        N, d = P.shape
        ns = loads.shape[0]
        D = 3 * N + d
        lu, ap = step.lu, step.ap
        G = np.hstack([lu.solve(step.A_all.toarray()), lu.solve(alpha * P)])  # q_lin = G s + L load
        Zp = lu.solve(P)
        Lload = lu.solve(np.asarray(loads, dtype=float).T)  # (N, ns)
        eu = np.zeros((N, D))
        ev = np.zeros((N, D))
        ea = np.zeros((N, D))
        eu[:, :N] = np.eye(N)
        ev[:, N : 2 * N] = np.eye(N)
        ea[:, 2 * N : 3 * N] = np.eye(N)
        T = np.zeros((D, D))
        T[:N] = G
        T[2 * N : 3 * N] = step.a1 * (G - eu) - step.a2 * ev - step.a3 * ea
        T[N : 2 * N] = step.b1 * (G - eu) + step.b2 * ev + step.b3 * ea
        B = np.zeros((D, d))
        B[:N] = -ap * Zp
        B[2 * N : 3 * N] = -step.a1 * ap * Zp
        B[N : 2 * N] = -step.b1 * ap * Zp
        B[3 * N :] = np.eye(d)
        F = np.zeros((D, ns))
        F[:N] = Lload
        F[2 * N : 3 * N] = step.a1 * Lload
        F[N : 2 * N] = step.b1 * Lload
        C = P.T @ G  # (d, D)
        R = np.empty((ns, d, D))  # C Tⁿ
        psi = np.empty((ns, d))
        r = np.zeros(D)
        row = C
        for n in range(ns):
            R[n] = row
            psi[n] = C @ r + P.T @ Lload[:, n]
            r = T @ r + F[:, n]
            row = row @ T
        E = np.empty((ns, D, d))  # T^{ns-1-m} B
        col = B
        for m in range(ns - 1, -1, -1):
            E[m] = col
            col = T @ col
        K = R @ B  # (ns, d, d): kernel C T^k B
        # reversed kernel blocks, so that step n sums K[n-1-m] g_m as one dot product
        self.kernel = K[::-1].transpose(1, 0, 2).reshape(d, ns * d)
        self.R = R.reshape(ns * d, D)
        self.psi = psi
        self.E = E.transpose(1, 0, 2).reshape(D, ns * d)
        self.Phi = np.linalg.matrix_power(T, ns)
        self.r_end = r
        self.S = P.T @ Zp
        self.P = P
        self.N, self.d, self.ns = N, d, ns

    def run(self, s0: NDArray, solve_links: Callable[[NDArray, int], tuple[NDArray, NDArray]]):
        """One period from the extended state ``s0``.

        Parameters
        ----------
        s0 : ndarray (3N + d,)
            (q, q', q'', g_prev) at the start of the period.
        solve_links : callable
            ``solve_links(y_lin, j)`` returns (y, g), the link coordinates and forces at
            the end of step j (phase j + 1) given the linear prediction ``y_lin`` (floats
            when d = 1, arrays of d otherwise).

        Returns
        -------
        y : ndarray (d, ns)
            Link coordinates at the start of each step.
        s : ndarray (3N + d,)
            The extended state at the end of the period.
        """
        d, ns = self.d, self.ns
        base = (self.R @ s0).reshape(ns, d) + self.psi
        g = np.zeros(ns * d)
        y = np.empty((d, ns))
        y[:, 0] = self.P.T @ s0[: self.N]
        kernel = self.kernel
        if d == 1:  # scalar links: floats, one dot product per step
            k1, b1, y1 = kernel[0], base[:, 0].tolist(), y[0]
            for n in range(ns):
                yn, gn = solve_links(b1[n] + float(k1[ns - n :] @ g[:n]) if n else b1[0], n)
                g[n] = gn
                if n + 1 < ns:
                    y1[n + 1] = yn
        else:
            for n in range(ns):
                y_lin = base[n] + kernel[:, (ns - n) * d :] @ g[: n * d] if n else base[n]
                yn, gn = solve_links(y_lin, n)
                g[n * d : (n + 1) * d] = gn
                if n + 1 < ns:
                    y[:, n + 1] = yn
        s = self.Phi @ s0 + self.E @ g + self.r_end
        return y, s

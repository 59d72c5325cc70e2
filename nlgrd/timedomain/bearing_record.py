"""The linear bearings' displacements and forces along a link model's integration, step by
step: what :mod:`nlgrd.timedomain.time_answer` turns into the same bearing outputs a
harmonic-balance row has (:data:`nlgrd.nonlinear.results.bearing_loads.BEARING_OUTPUTS`).

The HHT-α recurrence is linear in the state and the link forces, so a bearing node's
displacement at every step of a period is an affine function of the period's start state
s₀ and the link forces g_m it solved (:class:`nlgrd.timedomain.period_map.PeriodMap`, whose
construction is reused with the bearing DOFs added as outputs of zero force):
q_b(n+1) = R_b Tⁿ s₀ + ψ_b(n) + Σ_{m<n} K_b(n-1-m) g_m - α_p S_b g_n. The whole period is
one matrix product after the period has run. Velocities follow from the Newmark update
of the step (exact, the update being linear), forces are -(K_b q + C_b q') of each bearing
at its own shaft speed (:func:`nlgrd.nonlinear.results.bearing_loads.bearing_forces`, in
the time domain). A model too large for a period map is stepped on all DOFs
(:meth:`nlgrd.timedomain.links.LinkIntegrator.stepped`, the bearing DOFs recorded).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from nlgrd.nonlinear.results.bearing_loads import bearing_names, bearing_node_dofs
from nlgrd.timedomain.links import LinkIntegrator
from nlgrd.timedomain.period_map import PeriodMap

#: Largest convolution matrix (entries) built for a period; above it the period is stepped.
MAX_CONVOLUTION = 20_000_000


class BearingRecord:
    """Per-step displacements and forces of the linear bearings' nodes of a link model.

    Parameters
    ----------
    integ : LinkIntegrator
        The integration whose periods are recorded.

    Attributes
    ----------
    names : list of str
        The bearings' names (:func:`~nlgrd.nonlinear.results.bearing_loads.bearing_names`).
    dofs : ndarray of int (2 n_b,)
        Their nodes' (u_y, u_z) DOFs.
    """

    def __init__(self, integ: LinkIntegrator):
        self.integ = integ
        system = integ.model.system
        self.names = bearing_names(system)
        self.dofs = bearing_node_dofs(system)
        speed = integ.model.receptance.plan.speed(integ.omega)
        shafts = system.shafts
        self._K = [b.stiffness(shafts[b.shaft].speed_ratio * speed) for b in system.bearings]
        self._C = [b.damping(shafts[b.shaft].speed_ratio * speed) for b in system.bearings]
        self._map = None
        self._newmark = None
        nb2, ns, d = self.dofs.size, integ.ns, integ.d
        if nb2 and integ.pmap is not None and (ns * nb2) * (ns * d) <= MAX_CONVOLUTION:
            self._map = self._output_map()

    def _output_map(self) -> tuple[NDArray, NDArray, NDArray]:
        """(R_b, ψ_b, the block lower-triangular convolution) of the bearing DOFs over a
        period, from a period map of the link directions and the bearing DOFs together."""
        integ = self.integ
        N, d, ns, nb2 = integ.N, integ.d, integ.ns, self.dofs.size
        E = np.zeros((N, nb2))
        E[self.dofs, np.arange(nb2)] = 1.0
        ap = integ.step.ap
        loads = ap * np.roll(integ.F, -1, axis=0) - integ.alpha * integ.F  # as LinkIntegrator's map
        pm = PeriodMap(integ.step, integ.alpha, np.hstack([integ.P, E]), loads)
        da = d + nb2
        R = pm.R.reshape(ns, da, 3 * N + da)[:, d:, : 3 * N + d].reshape(ns * nb2, 3 * N + d)
        psi = pm.psi[:, d:].reshape(-1)
        K = pm.kernel.reshape(da, ns, da)[:, ::-1, :].transpose(1, 0, 2)[:, d:, :d]  # K[k]: C Tᵏ B
        conv = np.zeros((ns, nb2, ns, d))
        for n in range(ns):
            conv[n, :, n] = -ap * pm.S[d:, :d]  # the step's own force
            if n:
                conv[n, :, :n] = K[n - 1 :: -1].transpose(1, 0, 2)  # g_m with K[n-1-m]
        return R, psi, conv.reshape(ns * nb2, ns * d)

    def period(self, s: NDArray) -> tuple[NDArray, NDArray, NDArray]:
        """One period of the integration from the extended state ``s``, recorded.

        Parameters
        ----------
        s : ndarray (3N + d,)
            The extended state at the start of the period.

        Returns
        -------
        y : ndarray (d, ns)
            Link coordinates at the start of each step [m].
        q : ndarray (2 n_b, ns)
            The bearing nodes' (u_y, u_z) at the start of each step [m].
        s : ndarray (3N + d,)
            The extended state at the end of the period.
        """
        integ = self.integ
        if self._map is None:
            if integ.pmap is not None and not self.dofs.size:
                y, s_end = integ.period(s)
                return y, np.empty((0, integ.ns)), s_end
            return integ.stepped(s, output_dofs=self.dofs)
        y, g, s_end = integ.period_forces(s)
        R, psi, conv = self._map
        nb2 = self.dofs.size
        after = (R @ s + psi + conv @ g.reshape(-1)).reshape(integ.ns, nb2)  # phases 1..ns
        q = np.empty((nb2, integ.ns))
        q[:, 0] = s[self.dofs]
        q[:, 1:] = after[:-1].T
        return y, q, s_end

    def velocities(self, q: NDArray, s: NDArray) -> NDArray:
        """The bearing DOFs' velocities at the steps of a period: the Newmark update of the
        HHT-α step from the period's start velocity and acceleration.

        Parameters
        ----------
        q : ndarray (2 n_b, ns)
            Their displacements at the start of each step [m].
        s : ndarray (3N + d,)
            The extended state at the start of the period.

        Returns
        -------
        ndarray (2 n_b, ns)
            [m/s].
        """
        N = self.integ.N
        if self._newmark is None:
            self._newmark = self._velocity_map(q.shape[1])
        cv, ca, W = self._newmark
        return np.outer(s[N + self.dofs], cv) + np.outer(s[2 * N + self.dofs], ca) + np.diff(q, axis=1) @ W

    def _velocity_map(self, ns: int) -> tuple[NDArray, NDArray, NDArray]:
        """The Newmark update (v, a)_{j+1} = A (v, a)_j + b Δq_j unrolled over a period:
        v_n = (Aⁿ)₀₀ v₀ + (Aⁿ)₀₁ a₀ + Σ_{j<n} (A^{n-1-j} b)₀ Δq_j."""
        st = self.integ.step
        A = np.array([[st.b2, st.b3], [-st.a2, -st.a3]])
        b = np.array([st.b1, st.a1])
        cv, ca, h = np.empty(ns), np.empty(ns), np.empty(ns)
        Ak = np.eye(2)
        for k in range(ns):
            cv[k], ca[k], h[k] = Ak[0, 0], Ak[0, 1], (Ak @ b)[0]
            Ak = A @ Ak
        W = np.zeros((ns - 1, ns))
        for j in range(ns - 1):
            W[j, j + 1 :] = h[: ns - 1 - j]
        return cv, ca, W

    def forces(self, q: NDArray, v: NDArray) -> NDArray:
        """Each bearing's (y, z) force on its node, -(K_b q + C_b q') [N], (2 n_b, ns).

        Parameters
        ----------
        q, v : ndarray (2 n_b, ns)
            The bearing DOFs' displacements [m] and velocities [m/s].

        Returns
        -------
        ndarray (2 n_b, ns)
        """
        f = np.empty_like(q)
        for j, (K, C) in enumerate(zip(self._K, self._C, strict=True)):
            sl = slice(2 * j, 2 * j + 2)
            f[sl] = -(K @ q[sl] + C @ v[sl])
        return f

"""A harmonic-balance orbit polished by shooting on the exact piecewise-linear flow (issue 35).

Floquet multipliers computed from a harmonic-balance orbit take its contact times from the
truncated Fourier series; with a stiff contact these are off by far more than the orbit's
amplitudes (a stop of 100 x the chain's stiffness needs H >= 75 for the right verdict).
:func:`shoot_orbit` starts from the harmonic-balance orbit and finds the exact periodic
orbit of the same equations

    M q'' + D q' + K q = F₀ - Σ_i w_i k_i f_i(w_iᵀ q - e_i(θ)) + Σ_i w_i c_i e_i'(t),  θ = ω t,

f_i the backlash law (drive side x - b, back side x + b, nothing between; a contact stop
has no back side), by Newton on the period map s(T) - s(0), s = (q, q'), with the
monodromy Φ as its Jacobian. Between contact changes the equations are linear with
harmonic forcing, so the flow is exact: the periodic particular solution plus the modal
exponentials of the state matrix. The contact changes are found on the flow itself (the
gap sampled ``n_samples`` times per period, a Hermite test for a double crossing inside a
sample step, then bracketed Newton to 1e-13 T), not taken from the harmonic-balance
orbit. The contact force is continuous, so the saltation matrix at a change is the
identity (Leine & Nijmeijer 2004, Dynamics and Bifurcations of Non-Smooth Mechanical
Systems, §3.5) and Φ is the product of the flows' Jacobians; its eigenvalues are the
multipliers of the exact orbit.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike, NDArray

from nlgrd.errors import ModelError
from nlgrd.nonlinear.fourier.harmonics import analyse, n_harmonics, real_to_complex
from nlgrd.nonlinear.laws.force_laws import BacklashMesh, ContactStop, ParametricMesh

if TYPE_CHECKING:  # pragma: no cover
    from nlgrd.nonlinear.hb.harmonic_balance import ReducedModel
    from nlgrd.nonlinear.reduction.state_space import LinearStateSpace

#: Contact changes are located to this fraction of the period.
EVENT_RTOL = 1e-13
#: Contact changes in a row with no time between them (each within EVENT_RTOL of the
#: period) after which the flow is stuck: where each contact state's margin leaves that
#: state at once (a tangency that :meth:`_Flow._after_entry` finds no positive margin to
#: bracket), the event search would flip between them at one instant forever (before
#: _after_entry, the preloaded chain of tests/test_folds.py near 1.4324 rad/s did). A law
#: switches once per instant, so more changes in a row than this are a cycle: the flow
#: returns NaN (no orbit through it) instead. Far above the laws of any model.
STILL_EVENTS = 50
#: Points at which the margin is sampled inside a step that a trajectory enters and leaves
#: (:meth:`_Flow._after_entry`), as the Hermite test of a double crossing samples (32).
ENTRY_SAMPLES = 32


@dataclass(frozen=True)
class ShootingOrbit:
    """The exact periodic orbit found by :func:`shoot_orbit`.

    Attributes
    ----------
    state : ndarray (2N,)
        (q, q') at θ = 0 [m, m/s] (per DOF unit).
    multipliers : ndarray of complex
        Eigenvalues of the monodromy Φ [-].
    monodromy : ndarray (2N, 2N)
        Φ = ∂s(T)/∂s(0) of the state (q, q').
    switch_angles : ndarray
        Angles θ of the contact changes over one period [rad].
    residual : float
        Relative period-map residual max|s(T) - s(0)| / max|s| (velocities divided by ω) [-].
    iterations : int
        Newton iterations.
    converged : bool
        ``residual`` <= ``tol``.
    """

    state: NDArray
    multipliers: NDArray
    monodromy: NDArray
    switch_angles: NDArray
    residual: float
    iterations: int
    converged: bool


@dataclass(frozen=True)
class _Law:
    index: int  # nonlinear coordinate
    stiffness: float
    gap: float
    back: bool  # has a back-side contact
    lste: NDArray  # complex amplitudes E_j, j = 0..L
    damping: float


def _laws(nonlinearities: Sequence) -> list[_Law]:
    out = []
    for nl in nonlinearities:
        if not isinstance(nl, BacklashMesh) or isinstance(nl, ParametricMesh):
            raise ModelError(
                "nonlinearities", f"shooting needs backlash or contact-stop laws, got {type(nl).__name__}"
            )
        out.append(
            _Law(
                int(nl.coords[0]),
                float(nl.stiffness),
                float(nl.half_backlash),
                not isinstance(nl, ContactStop),
                real_to_complex(nl.lste),
                float(nl.damping),
            )
        )
    return out


class _Flow:
    """The exact flow of the state space with the laws at ω: per contact state (a tuple of
    -1, 0, 1 per law) the state matrix, its eigendecomposition and the periodic particular
    solution."""

    def __init__(self, ss: LinearStateSpace, laws: list[_Law], F0: NDArray, omega: float, n_samples: int):
        self.ss, self.laws, self.omega = ss, laws, float(omega)
        self.T = 2 * np.pi / self.omega
        self.dt = self.T / n_samples
        self.N = ss.M.shape[0]
        self.L = max(law.lste.size for law in laws) - 1
        self.F0 = F0
        self.Minv = np.linalg.inv(ss.M)
        self._cache: dict = {}

    def _e(self, law: _Law, t: float, derivative: int = 0) -> float:
        j = np.arange(law.lste.size)
        return float(
            np.real(np.sum(law.lste * (1j * j * self.omega) ** derivative * np.exp(1j * j * self.omega * t)))
        )

    def data(self, sigma: tuple):
        if sigma not in self._cache:
            N, ss = self.N, self.ss
            Kt = ss.K.copy()
            F = np.zeros((self.L + 1, N), dtype=complex)
            F[0] += self.F0
            j = np.arange(self.L + 1)
            for law, s in zip(self.laws, sigma, strict=True):
                w = ss.W[:, law.index]
                E = np.zeros(self.L + 1, dtype=complex)
                E[: law.lste.size] = law.lste
                F += np.outer(1j * j * self.omega * law.damping * E, w)
                if s:
                    Kt += law.stiffness * np.outer(w, w)
                    E = E.copy()
                    E[0] += s * law.gap
                    F += np.outer(law.stiffness * E, w)
            A = np.zeros((2 * N, 2 * N))
            A[:N, N:] = np.eye(N)
            A[N:, :N] = -self.Minv @ Kt
            A[N:, N:] = -self.Minv @ ss.D
            B = np.zeros((self.L + 1, 2 * N), dtype=complex)
            B[:, N:] = F @ self.Minv.T
            if np.linalg.cond(A) > 1e12:
                raise ModelError("state_space", "a free rigid-body mode: shoot on the deflated state space")
            P = np.array(
                [np.linalg.solve(1j * k * self.omega * np.eye(2 * N) - A, B[k]) for k in range(self.L + 1)]
            )
            lam, V = np.linalg.eig(A)
            self._cache[sigma] = (A, lam, V, np.linalg.inv(V), P)
        return self._cache[sigma]

    def particular(self, sigma, t: float) -> NDArray:
        P = self.data(sigma)[4]
        k = np.arange(P.shape[0])
        return np.real(np.exp(1j * k * self.omega * t) @ P)

    def at(self, sigma, t0: float, s0: NDArray, tau: float) -> tuple[NDArray, NDArray]:
        """(s(t0 + τ), ∂s(t0 + τ)/∂s(t0)) in state σ."""
        _, lam, V, Vi, _ = self.data(sigma)
        E = np.real((V * np.exp(lam * tau)) @ Vi)
        return self.particular(sigma, t0 + tau) + E @ (s0 - self.particular(sigma, t0)), E

    def margins(self, sigma, t: float, s: NDArray, derivative: bool = False) -> NDArray:
        """Per law and boundary, the signed distance to leaving state σ (> 0 inside)."""
        out = []
        for law, sg in zip(self.laws, sigma, strict=True):
            w = self.ss.W[:, law.index]
            if derivative:  # x' = wᵀ q' - e'
                x = w @ s[self.N :] - self._e(law, t, 1)
            else:
                x = w @ s[: self.N] - self._e(law, t)
            g = 0.0 if derivative else law.gap
            if sg == 1:
                out.append(x - g)
            elif sg == -1:
                out.append(-x - g)
            else:
                out.append(g - x)
                if law.back:
                    out.append(x + g)
        return np.array(out)

    def next_state(self, sigma, which: int) -> tuple:
        k, new = 0, list(sigma)
        for i, (law, sg) in enumerate(zip(self.laws, sigma, strict=True)):
            n = 2 if (sg == 0 and law.back) else 1
            if k <= which < k + n:
                new[i] = 0 if sg else (1 if which == k else -1)
                return tuple(new)
            k += n
        raise AssertionError("boundary index out of range")

    def state_at(self, t: float, s: NDArray) -> tuple:
        sigma = []
        for law in self.laws:
            x = self.ss.W[:, law.index] @ s[: self.N] - self._e(law, t)
            sigma.append(1 if x > law.gap else (-1 if law.back and x < -law.gap else 0))
        return tuple(sigma)

    def period(self, s: NDArray) -> tuple[NDArray, NDArray, NDArray]:
        """s(T), Φ and the contact-change times from s(0) = s."""
        s, Phi, events, _ = self.run(s, 0.0, self.T)
        return s, Phi, events

    def run(self, s: NDArray, t0: float, t1: float, sigma: tuple | None = None):
        """s(t1), ∂s(t1)/∂s(t0), the contact-change times and the contact state at t1
        (s(t1) and ∂s(t1)/∂s(t0) NaN where the flow is stuck: :data:`STILL_EVENTS`)."""
        t = t0
        sigma = self.state_at(t0, s) if sigma is None else sigma
        Phi, events, still = np.eye(s.size), [], 0
        while t < t1 - 1e-15 * self.T:
            step = min(self.dt, t1 - t)
            sn, E = self.at(sigma, t, s, step)
            m0, m1 = self.margins(sigma, t, s), self.margins(sigma, t + step, sn)
            hit = np.nonzero(m1 < 0)[0]
            if hit.size == 0:  # a double crossing inside the step (cubic Hermite of the margins)
                d0 = self.margins(sigma, t, s, True) * step
                d1 = self.margins(sigma, t + step, sn, True) * step
                r = np.linspace(0, 1, 33)[1:-1, None]
                hh = (
                    (2 * r**3 - 3 * r**2 + 1) * m0
                    + (r**3 - 2 * r**2 + r) * d0
                    + (-2 * r**3 + 3 * r**2) * m1
                    + (r**3 - r**2) * d1
                )
                bad = np.argwhere(hh < 0)
                if bad.size:
                    step = float(r[bad[0, 0], 0] * step)
                    hit = np.array([bad[0, 1]])
            if hit.size:
                tau, which = self._locate(sigma, t, s, step, hit)
                still = still + 1 if tau <= EVENT_RTOL * self.T else 0
                if still > STILL_EVENTS:  # stuck at a grazing (STILL_EVENTS): no orbit through it
                    nan = np.full(s.size, np.nan)
                    return nan, np.full((s.size, s.size), np.nan), np.array(events), sigma
                s, E = self.at(sigma, t, s, tau)
                Phi = E @ Phi  # saltation = identity: the contact force is continuous
                t += tau
                events.append(t)
                sigma = self.next_state(sigma, which)
                continue
            Phi = E @ Phi
            s, t = sn, t + step
        return s, Phi, np.array(events), sigma

    def samples(self, s: NDArray, n: int) -> NDArray:
        """The nonlinear coordinates y = Wᵀ q at θ_j = 2πj/n along the orbit from s(0) = s, (n_nl, n)."""
        out = np.empty((self.ss.W.shape[1], n))
        sigma, t = None, 0.0
        for j in range(n):
            if j:
                s, _, _, sigma = self.run(s, t, j * self.T / n, sigma)
                t = j * self.T / n
            out[:, j] = self.ss.W.T @ s[: self.N]
        return out

    def _after_entry(self, sigma, t, s, step, i, bracket):
        """A bracket (a, m(a), b, m(b)) of the zero of margin ``i`` after the trajectory has
        entered σ at t (its margin 0 there, < 0 at the step's end: it leaves again within
        the step, e.g. a contact shorter than the step at a grazing touch): the first of
        :data:`ENTRY_SAMPLES` points inside the step where the margin is positive, and the
        next where it is not; ``bracket`` (the start's zero) when none is positive (the
        trajectory leaves σ at once)."""
        r = np.arange(1, ENTRY_SAMPLES + 1) * step / ENTRY_SAMPLES
        m = np.array([self.margins(sigma, t + x, self.at(sigma, t, s, x)[0])[i] for x in r])
        inside = np.nonzero(m > 0)[0]
        if inside.size:
            k = int(inside[0])
            out = np.nonzero(m[k:] <= 0)[0]
            if out.size:
                j = k + int(out[0])
                return float(r[k]), float(m[k]), float(r[j]), float(m[j])
        return bracket

    def _locate(self, sigma, t, s, step, hit) -> tuple[float, int]:
        """The earliest zero in (0, step] of the margins ``hit``, by bracketed Newton."""
        best = (step, int(hit[0]))
        for i in hit:
            a, b = 0.0, step
            ma = self.margins(sigma, t, s)[i]
            mb = self.margins(sigma, t + b, self.at(sigma, t, s, b)[0])[i]
            if mb >= 0:  # inside the step by the Hermite test: bisect its first dip
                b = step
            if ma <= 0:  # on the boundary just crossed into σ: the zero sought is the next one
                a, ma, b, mb = self._after_entry(sigma, t, s, step, i, (a, ma, b, mb))
            tau = a + (b - a) * ma / (ma - mb) if ma != mb else 0.5 * (a + b)
            for _ in range(100):
                st = self.at(sigma, t, s, tau)[0]
                g = self.margins(sigma, t + tau, st)[i]
                if g > 0:
                    a = tau
                else:
                    b = tau
                d = self.margins(sigma, t + tau, st, True)[i]
                new = tau - g / d if d != 0 else 0.5 * (a + b)
                if not a < new < b:
                    new = 0.5 * (a + b)
                if abs(new - tau) < EVENT_RTOL * self.T or b - a < EVENT_RTOL * self.T:
                    tau = new
                    break
                tau = new
            if tau < best[0]:
                best = (tau, int(i))
        return best


def initial_state(
    state_space: LinearStateSpace,
    nonlinearities: Sequence,
    harmonics: ArrayLike,
    omega: float,
    static_force: ArrayLike | None = None,
) -> NDArray:
    """(q, q') at θ = 0 of a harmonic-balance orbit, recovered from its nonlinear coordinates:
    Q_k = Z_k⁻¹ (F_k - Σ_i w_i G_ik), G_i the exact force harmonics of law i.

    Parameters
    ----------
    state_space : LinearStateSpace
        M, D, K and W of the model (no free rigid-body mode).
    nonlinearities : sequence
        The force laws (:class:`BacklashMesh` or :class:`ContactStop`, constant stiffness).
    harmonics : array_like (n_nl, 2H+1)
        Real harmonics of the nonlinear coordinates [m].
    omega : float
        Base frequency ω [rad/s].
    static_force : array_like (N,), optional
        F₀ [N] (default zero).

    Returns
    -------
    ndarray (2N,)
        (q, q') at θ = 0 [m, m/s].
    """
    ss = state_space
    N = ss.M.shape[0]
    Y = np.atleast_2d(np.asarray(harmonics, dtype=float))
    H = n_harmonics(Y[0])
    F0 = np.zeros(N) if static_force is None else np.asarray(static_force, dtype=float).reshape(N)
    F = np.zeros((H + 1, N), dtype=complex)
    F[0] += F0
    k = np.arange(H + 1)
    for nl in nonlinearities:
        i = int(nl.coords[0])
        G = real_to_complex(nl.harmonics(Y[i])[0])
        E = np.zeros(H + 1, dtype=complex)
        e = real_to_complex(nl.lste)[: H + 1]
        E[: e.size] = e
        F -= np.outer(G, ss.W[:, i])
        F += np.outer(1j * k * omega * nl.damping * E, ss.W[:, i])
    q = np.linalg.lstsq(ss.K, F[0].real, rcond=None)[0]
    v = np.zeros(N)
    for kk in range(1, H + 1):
        Q = np.linalg.solve(ss.K - (kk * omega) ** 2 * ss.M + 1j * kk * omega * ss.D, F[kk])
        q += Q.real
        v += (1j * kk * omega * Q).real
    return np.concatenate([q, v])


def shoot_orbit(
    state_space: LinearStateSpace,
    nonlinearities: Sequence,
    harmonics: ArrayLike | None,
    omega: float,
    static_force: ArrayLike | None = None,
    *,
    tol: float = 1e-11,
    max_iter: int = 30,
    n_samples: int = 256,
    state: ArrayLike | None = None,
) -> ShootingOrbit:
    """The exact periodic orbit near a harmonic-balance orbit, and its Floquet multipliers.

    Newton on s(T) - s(0) from :func:`initial_state` (or from ``state``), Jacobian Φ - I, on the exact flow
    (module docstring). The period is 2π/ω of the model's base: a period-ν model (base
    ω/ν, excitation spread to harmonic ν) is shot over its whole period.

    Parameters
    ----------
    state_space : LinearStateSpace
        M, D, K and W (``ReducedModel.linear_state_space(omega)``); no free rigid-body mode.
    nonlinearities : sequence
        The force laws (:class:`BacklashMesh` or :class:`ContactStop`, constant stiffness).
    harmonics : array_like (n_nl, 2H+1)
        Real harmonics of the nonlinear coordinates of the harmonic-balance orbit [m].
    omega : float
        Base frequency ω [rad/s].
    static_force : array_like (N,), optional
        F₀ [N] (default zero).
    tol : float
        Newton's tolerance on the relative period-map residual [-].
    max_iter : int
        Newton iterations at most.
    n_samples : int
        Gap samples per period of the event search [-].
    state : array_like (2N,), optional
        Start (q, q') at θ = 0 [m, m/s] instead of the harmonic-balance orbit's (which may
        then be None).

    Returns
    -------
    ShootingOrbit
        The orbit, its monodromy and multipliers, the contact-change angles.

    Raises
    ------
    ModelError
        A law other than the backlash or contact-stop law, or a state matrix that a free
        rigid-body mode makes singular.
    """
    ss = state_space
    N = ss.M.shape[0]
    F0 = np.zeros(N) if static_force is None else np.asarray(static_force, dtype=float).reshape(N)
    flow = _Flow(ss, _laws(nonlinearities), F0, omega, n_samples)
    if state is None:
        s = initial_state(ss, nonlinearities, harmonics, omega, F0)
    else:
        s = np.array(state, dtype=float).reshape(2 * N)
    scale = np.concatenate([np.ones(N), np.full(N, 1 / omega)])

    def error(r, s):
        return float(np.max(np.abs(r * scale)) / max(np.max(np.abs(s * scale)), 1e-300))

    for it in range(max_iter + 1):
        end, Phi, events = flow.period(s)
        r = end - s
        if not np.all(np.isfinite(r)):  # the flow is stuck at a grazing: no orbit
            return ShootingOrbit(s, np.full(2 * N, np.nan + 0j), Phi, omega * events, np.inf, it, False)
        err = error(r, s)
        if err <= tol or it == max_iter:
            break
        s = s - np.linalg.solve(Phi - np.eye(2 * N), r)
    return ShootingOrbit(s, np.linalg.eigvals(Phi), Phi, omega * events, err, it, bool(err <= tol))


def shootable(model: ReducedModel) -> bool:
    """Whether the exact flow of ``model`` is known: its static force is given and every law
    is a backlash or contact-stop law of constant stiffness.

    Parameters
    ----------
    model : ReducedModel
        The reduced model.

    Returns
    -------
    bool
    """
    return (
        model.static_force is not None
        and bool(model.nonlinearities)
        and all(
            isinstance(nl, BacklashMesh) and not isinstance(nl, ParametricMesh) for nl in model.nonlinearities
        )
    )


def polish(model: ReducedModel, harmonics: ArrayLike, omega: float) -> ShootingOrbit | None:
    """:func:`shoot_orbit` on ``model`` from a harmonic-balance orbit; None where the model is
    not :func:`shootable`, its state space is singular or Newton did not converge.

    Parameters
    ----------
    model : ReducedModel
        The reduced model (its ``linear_state_space`` and ``static_force``).
    harmonics : array_like (n_nl, 2H+1)
        Real harmonics of the nonlinear coordinates [m].
    omega : float
        Base frequency ω [rad/s].

    Returns
    -------
    ShootingOrbit or None
    """
    if not shootable(model):
        return None
    ss = model.linear_state_space(omega)
    if ss is None:
        return None
    try:
        orbit = shoot_orbit(ss, model.nonlinearities, harmonics, omega, model.static_force)
    except (ModelError, np.linalg.LinAlgError):
        return None
    return orbit if orbit.converged else None


def orbit_harmonics(model: ReducedModel, orbit: ShootingOrbit, omega: float, H: int) -> NDArray:
    """The harmonics 0..H of the nonlinear coordinates along a shot orbit (sampled on the exact
    flow at max(8H, 256) angles).

    Parameters
    ----------
    model : ReducedModel
        The model it was shot on.
    orbit : ShootingOrbit
        From :func:`polish` or :func:`shoot_orbit`.
    omega : float
        Base frequency ω [rad/s].
    H : int
        Number of harmonics.

    Returns
    -------
    ndarray (n_nl, 2H+1)
        Real harmonics [m].
    """
    return analyse(model_flow(model, omega).samples(orbit.state, max(8 * H, 256)), H)


def model_flow(model: ReducedModel, omega: float) -> _Flow:
    """The exact flow of a reduced model at base frequency ω (its linear state space, laws
    and static force; 256 cells a period).

    Parameters
    ----------
    model : ReducedModel
        A :func:`shootable` model.
    omega : float
        Base frequency ω [rad/s].

    Returns
    -------
    _Flow
        Its period map, monodromy and samples.
    """
    ss = model.linear_state_space(omega)
    N = ss.M.shape[0]
    F0 = np.zeros(N) if model.static_force is None else np.asarray(model.static_force, dtype=float).reshape(N)
    return _Flow(ss, _laws(model.nonlinearities), F0, omega, 256)


def shooting_start(model: ReducedModel, omega: float, H: int) -> NDArray | None:
    """A start for Newton where the linear one fails: the exact orbit shot from the linear
    response (a contact stop without preload: its full-contact start sits at the stop, where
    the harmonic-balance Newton does not converge), as H harmonics.

    Parameters
    ----------
    model : ReducedModel
        The reduced model.
    omega : float
        Base frequency ω [rad/s].
    H : int
        Number of harmonics.

    Returns
    -------
    ndarray (n_nl, 2H+1) or None
        Real harmonics [m]; None where the model is not :func:`shootable` or shooting failed.
    """
    if not shootable(model):
        return None
    problem = model.at(omega, H)
    z = problem.linear_solution().reshape(problem.n_coords, -1)
    orbit = polish(model, z, omega)
    return None if orbit is None else orbit_harmonics(model, orbit, omega, H)

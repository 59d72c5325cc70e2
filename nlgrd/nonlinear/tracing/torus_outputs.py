"""The torus of a one-mesh geared FE model and what a torus reports: the mesh outputs
averaged over it and its bearings' loads.

The torus is the two-frequency harmonic balance of :mod:`nlgrd.nonlinear.hb.quasi_periodic` on
the mesh coordinate of the receptance-reduced model
(:func:`nlgrd.nonlinear.models.geared.build_geared_model`), the linear part entering through
h(Ω) = wᵀ Z(Ω)⁻¹ w at each combination frequency Ω (Z of the full FE model at the shaft
speed of ω₁, with the mesh damping, without k_h: the matrix of the periodic harmonic
balance's direct receptance). Its outputs are sampled on the torus (time averages of the
quasi-periodic motion). :class:`GearedTorus` bundles them for
:mod:`nlgrd.nonlinear.tracing.torus_sweep`; :mod:`nlgrd.nonlinear.tracing.link_torus` is the
same for a model with any links, one mesh too, and the one the library uses (issue 33:
:class:`GearedTorus`, :func:`geared_torus_model`, :func:`torus_bearing_forces` and
:func:`torus_bearing_outputs` are the former one-mesh path, kept until the old engine goes).
The outputs (:func:`torus_outputs`, :func:`torus_back_contact`, the bearing statistics)
and κ(Ω) with its slope (:func:`kappa_and_slope`, :func:`dynamic_matrices`) serve both.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from numpy.typing import NDArray

from nlgrd.errors import ModelError
from nlgrd.nonlinear.hb import quasi_periodic as qp

#: Output names of a torus point, in the order of a torus sweep's outputs (SI), with the
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

    def kappa_slope_at(freqs: NDArray, omega: float) -> tuple[NDArray, NDArray]:
        return kappa_and_slope(rec.model, W, freqs, rec.speed(omega))

    red = model.reduced
    return qp.TorusModel(kappa_at, red.kappa, red.force, red.nonlinearities, kappa_slope_at=kappa_slope_at)


def dynamic_matrices(linear, freqs: NDArray, speed: float, extra: sp.spmatrix | None = None):
    """Z(Ω) + i Ω ``extra`` at each frequency, one CSC matrix whose values are replaced
    in place (no sparse sum per frequency): the pattern of ``linear`` and ``extra``
    joined once, the values added entry by entry (the numbers of the sparse sum).

    Parameters
    ----------
    linear : LinearModel
        Its ``dynamic_stiffness_data`` on its ``pattern_entries``.
    freqs : ndarray (m,)
        Ω [rad/s].
    speed : float
        Reference shaft speed [rad/s].
    extra : sparse matrix (n, n), optional
        Added as i Ω times it [N s/m].

    Yields
    ------
    scipy.sparse.csc_matrix (n, n) complex
        The same object each time, valid until the next.
    """
    if not len(freqs):
        return
    Z = linear.dynamic_stiffness(float(freqs[0]), speed)
    if extra is None:
        for f in freqs:
            Z.data = linear.dynamic_stiffness_data(float(f), speed)
            yield Z
        return
    n = Z.shape[0]
    rows, cols = linear.pattern_entries
    E = sp.coo_matrix(extra)
    E.sum_duplicates()
    kz = np.asarray(cols, dtype=np.int64) * n + np.asarray(rows, dtype=np.int64)
    ke = E.col.astype(np.int64) * n + E.row.astype(np.int64)
    keys = np.union1d(kz, ke)  # column-major: CSC order
    pz, pe = np.searchsorted(keys, kz), np.searchsorted(keys, ke)
    indptr = np.concatenate([[0], np.cumsum(np.bincount(keys // n, minlength=n))])
    data = np.zeros(keys.size, dtype=complex)
    Z = sp.csc_matrix((data, (keys % n).astype(np.int32), indptr), shape=(n, n))
    for f in freqs:
        f = float(f)
        data = np.zeros(keys.size, dtype=complex)
        data[pz] = linear.dynamic_stiffness_data(f, speed)
        data[pe] += 1j * f * E.data
        Z.data = data
        yield Z


def kappa_and_slope(linear, W: NDArray, freqs: NDArray, speed: float, extra: sp.spmatrix | None = None):
    """κ(Ω) = (Wᵀ Z(Ω)⁻¹ W)⁻¹ and dκ/dΩ at a fixed speed, one sparse LU of Z per frequency:
    dκ = -κ (dh) κ, dh = -(Z⁻ᵀ W)ᵀ Z'(Ω) (Z⁻¹ W), Z' on the model's pattern
    (:meth:`~nlgrd.rotor.assembly.LinearModel.dynamic_stiffness_slope_data`). κ is the
    number a solve of ``linear.dynamic_stiffness`` (plus i Ω ``extra``) gives.

    Parameters
    ----------
    linear : LinearModel
        Its ``dynamic_stiffness`` is Z without ``extra``.
    W : ndarray (n, n_c)
        The coordinates' projection vectors.
    freqs : ndarray (m,)
        Ω [rad/s].
    speed : float
        Reference shaft speed [rad/s].
    extra : sparse matrix (n, n), optional
        Added to Z: i Ω times it (a link model's link damping) [N s/m].

    Returns
    -------
    kappa, slope : ndarray (m, n_c, n_c) complex
        [N/m], [N s/m].
    """
    Wc = W.astype(complex)
    nc = W.shape[1]
    kap = np.empty((len(freqs), nc, nc), dtype=complex)
    slope = np.empty_like(kap)
    rows, cols = linear.pattern_entries
    matrices = dynamic_matrices(linear, freqs, speed, extra)
    for i, (f, Z) in enumerate(zip(freqs, matrices, strict=True)):
        f = float(f)
        lu = spla.splu(Z)
        u = lu.solve(Wc)
        kap[i] = np.linalg.inv(W.T @ u)
        v = lu.solve(Wc, trans="T")
        d = linear.dynamic_stiffness_slope_data(f, speed)
        dh = -np.einsum("ri,r,rj->ij", v[rows], d, u[cols])
        if extra is not None:
            dh -= 1j * (v.T @ (extra @ u))
        slope[i] = -kap[i] @ dh @ kap[i]
    return kap, slope


class GearedTorus:
    """What :func:`~nlgrd.nonlinear.tracing.torus_sweep.torus_sweep` and
    :func:`~nlgrd.nonlinear.tracing.torus_sweep.converged_tori` need of a one-mesh geared model:
    its torus model, its periodic model and a torus's outputs and their convergence
    estimate. :class:`nlgrd.nonlinear.tracing.link_torus.LinkTorus` is the same for a link
    model; the sweep asks nothing else of either.

    Parameters
    ----------
    model : GearedModel
        From :func:`nlgrd.nonlinear.models.geared.build_geared_model` (period 1).

    Attributes
    ----------
    torus_model : TorusModel
        :func:`geared_torus_model`.
    reduced : ReducedModel
        The periodic model (its orbits and Floquet multipliers).
    bearing_names : list of str
        The bearings' names, as the sweep's columns.
    """

    def __init__(self, model):
        self.model = model
        self.torus_model = geared_torus_model(model)
        self.reduced = model.reduced
        self.bearing_names = [
            b.name or f"bearing {j} (shaft {b.shaft}, node {b.node})"
            for j, b in enumerate(model.system.bearings)
        ]

    def omegas(self, rpm: NDArray) -> NDArray:
        """Mesh frequencies [rad/s] of pinion speeds ``rpm`` [rpm]."""
        return self.model.mesh_frequency(rpm)

    def rpm(self, omegas: NDArray) -> NDArray:
        """Pinion speeds [rpm] of mesh frequencies ``omegas`` [rad/s]."""
        return self.model.pinion_rpm(omegas)

    def outputs(self, sol: qp.TorusSolution) -> NDArray:
        """:func:`torus_outputs` of the mesh (SI)."""
        return torus_outputs(sol, self.model.mesh)

    def change(
        self, outputs: NDArray, sol: qp.TorusSolution, fine: qp.TorusSolution
    ) -> tuple[NDArray, float]:
        """The relative change of the :data:`CHECKED` outputs from ``sol`` (whose
        ``outputs`` are given) to ``fine`` and the largest, the convergence estimate [-]."""
        idx = [list(TORUS_OUTPUTS).index(c) for c in CHECKED]
        ch = torus_outputs(fine, self.model.mesh)[idx] / outputs[idx] - 1
        return ch, float(np.max(np.abs(ch)))

    def bearing_force_max(self, sol: qp.TorusSolution) -> NDArray:
        """:func:`torus_bearing_forces` [N]."""
        return torus_bearing_forces(self.model, sol)

    def answer(self, sol: qp.TorusSolution, outputs: NDArray) -> tuple[dict, dict, dict]:
        """A torus's answer to a sweep point: the :data:`TORUS_OUTPUTS` with
        ``back_contact``, the bearings' outputs (:func:`torus_bearing_outputs`) and no
        link columns."""
        out = dict(zip(TORUS_OUTPUTS, outputs, strict=True))
        out["back_contact"] = torus_back_contact(sol, self.model.mesh)
        return out, torus_bearing_outputs(self.model, sol), {}


def torus_outputs(
    sol: qp.TorusSolution, mesh, n_samples: tuple[int, int] = (256, 48), coord: int = 0
) -> NDArray:
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
    coord : int
        The mesh's coordinate among the torus's (a link model's) [-].

    Returns
    -------
    ndarray (len(TORUS_OUTPUTS),)
        In the order of :data:`TORUS_OUTPUTS`; NaN when not converged.
    """
    if not sol.converged:
        return np.full(len(TORUS_OUTPUTS), np.nan)
    g = sol.grid
    fine = g.refined(n_samples)
    Y = sol.Y[coord : coord + 1]
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
    return Q, bearing_force_harmonics(system, Q, freqs, speed), freqs


def bearing_force_harmonics(system, Q: NDArray, freqs: NDArray, speed: float) -> NDArray:
    """The force of each bearing on its node, -(K_b + i Ω_k C_b) q_k, at every combination
    frequency Ω_k of a torus (each bearing at its own shaft's speed).

    Parameters
    ----------
    system : RotorSystem
        The model (its bearings, in order).
    Q : ndarray (|𝒦|, 2 n_b) complex
        The bearing nodes' (y, z) displacement harmonics [m].
    freqs : ndarray (|𝒦|,)
        Ω_k [rad/s].
    speed : float
        The reference shaft's speed [rad/s].

    Returns
    -------
    ndarray (|𝒦|, 2 n_b) complex
        [N].
    """
    Fb = np.empty_like(Q)
    for j, b in enumerate(system.bearings):
        s_b = system.shafts[b.shaft].speed_ratio * speed
        q = Q[:, 2 * j : 2 * j + 2]
        Fb[:, 2 * j : 2 * j + 2] = -(q @ b.stiffness(s_b).T + (1j * freqs)[:, None] * (q @ b.damping(s_b).T))
    return Fb


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
    return torus_bearing_statistics(Q, Fb, sol.grid, n_samples)


def torus_bearing_statistics(Q: NDArray, Fb: NDArray, grid, n_samples: tuple[int, int] = (256, 48)) -> dict:
    """Every bearing's outputs (:func:`torus_bearing_outputs`) from the 2-D harmonics of
    its node's (y, z) displacement and force on the torus's index set.

    Parameters
    ----------
    Q : ndarray (|𝒦|, 2 n_b) complex
        Displacement harmonics, (y, z) per bearing [m].
    Fb : ndarray (|𝒦|, 2 n_b) complex
        Force harmonics [N].
    grid : TorusGrid
        Their index set.
    n_samples : tuple of int
        Samples along θ₁ and θ₂ [-].

    Returns
    -------
    dict of str to ndarray (n_bearings,)
        As :func:`torus_bearing_outputs`.
    """
    nb = Q.shape[1] // 2
    fields = ("displacement_mean", "displacement_rms", "displacement_max")
    fields += ("force_mean", "force_rms", "force_max", "force_amplitude")
    g = grid
    fine = g.refined(n_samples)
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


def torus_back_contact(
    sol: qp.TorusSolution, mesh, n_samples: tuple[int, int] = (256, 48), coord: int = 0
) -> bool:
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
    coord : int
        The mesh's coordinate among the torus's [-].

    Returns
    -------
    bool
    """
    from nlgrd.nonlinear.fourier.harmonics import evaluate  # noqa: PLC0415
    from nlgrd.nonlinear.laws.force_laws import ContactStop  # noqa: PLC0415

    if not sol.converged or isinstance(mesh, ContactStop):
        return False
    g = sol.grid
    fine = g.refined(n_samples)
    d = fine.samples(sol.Y[coord : coord + 1])[0]
    e = evaluate(mesh.offset(max(g.H1, (mesh.lste.size - 1) // 2))[0], fine.theta1)
    return bool(np.any(d - e < -mesh.half_backlash))

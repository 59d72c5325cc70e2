"""What a torus reports, for :mod:`nlgrd.nonlinear.tracing.link_torus` (the torus of a model
with any links, one mesh too): the mesh outputs averaged over it (:func:`torus_outputs`,
:func:`torus_back_contact`), its bearings' loads (:func:`bearing_force_harmonics`,
:func:`torus_bearing_statistics`) and κ(Ω) with its slope at each combination frequency Ω
(:func:`kappa_and_slope`, :func:`dynamic_matrices`: Z of the full FE model at the shaft
speed of ω₁, with the links' damping, without their stiffness). The outputs are sampled on
the torus (time averages of the quasi-periodic motion).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from numpy.typing import NDArray

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
#: Bearing outputs below this fraction of the largest are rounding of the recovery.
BEARING_FLOOR = 1e-9


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


def torus_bearing_statistics(Q: NDArray, Fb: NDArray, grid, n_samples: tuple[int, int] = (256, 48)) -> dict:
    """Every bearing's outputs over a torus, the quantities of a periodic sweep's bearing
    columns: radial displacement and force of its node sampled on the torus (their largest,
    the RMS of the alternating part, the magnitude of the mean) and the amplitude of the
    force's base harmonic (k₁ = 1, k₂ = 0; the larger of y and z), from the 2-D harmonics of
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
        ``displacement_mean``, ``displacement_rms``, ``displacement_max`` [m],
        ``force_mean``, ``force_rms``, ``force_max``, ``force_amplitude`` [N].
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

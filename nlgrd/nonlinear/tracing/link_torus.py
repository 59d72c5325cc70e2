"""Quasi-periodic answers of a model with any links: the torus of
:mod:`nlgrd.nonlinear.hb.quasi_periodic` on all link coordinates of the receptance
reduction (:mod:`nlgrd.nonlinear.reduction.link_reduction`), and its outputs per link.

The linear part enters at each combination frequency Ω = k₁ ω₁ + k₂ ω₂ through
κ(Ω) = (Pᵀ Z(Ω)⁻¹ P)⁻¹, Z the dynamic stiffness of the linear model without the links'
stiffness, with their viscous damping, at the shaft speed of ω₁: the matrix whose values
at Ω = k ω₁ are the periodic reduction's κ_k. The forcing (the links' own, unbalance) is
ω₁-periodic and enters on the k₂ = 0 row only (Guillot, Vergez & Cochelin 2017, J. Sound
Vib. 394:434, for the two-frequency balance; Kim & Noah 1996, J. Appl. Mech. 63:375, for
its AFT). Every link's outputs are those of its periodic ``metrics`` taken over the
sampled torus (time averages of the quasi-periodic motion), every linear bearing's those
of :func:`nlgrd.nonlinear.results.bearing_loads.link_bearing_outputs`, from the bearing
nodes recovered at every Ω: on the k₂ = 0 row by the periodic recovery, elsewhere by
Q_k = Z(Ω_k)⁻¹ P κ(Ω_k) Y_k (no external force there, so G_k = -κ Y_k).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse.linalg as spla
from numpy.typing import NDArray

from nlgrd.errors import ModelError
from nlgrd.nonlinear.fourier.harmonics import complex_to_real, real_to_complex
from nlgrd.nonlinear.hb import quasi_periodic as qp
from nlgrd.nonlinear.results.bearing_loads import BEARING_OUTPUTS, bearing_names, bearing_node_dofs
from nlgrd.nonlinear.tracing.torus_outputs import (
    CHECKED,
    TORUS_OUTPUTS,
    bearing_force_harmonics,
    dynamic_matrices,
    kappa_and_slope,
    torus_back_contact,
    torus_bearing_statistics,
    torus_outputs,
)

#: The samples of a torus its outputs are taken on (θ₁, θ₂), as one mesh's.
SAMPLES = (256, 48)
#: An output below FLOOR x its physical scale (a clearance's) is compared relative to that
#: floor in the convergence estimate, as the periodic choice of H compares it
#: (:data:`nlgrd.nonlinear.tracing.harmonic_convergence.FLOOR`).
FLOOR = 1e-2


def _receptances(model, freqs: NDArray, omega: float) -> list[NDArray]:
    """Z(Ω)⁻¹ P (n, d) at each frequency, by a sparse LU of the full model."""
    rec = model.receptance
    P = rec.P.astype(complex)
    matrices = dynamic_matrices(rec.model, freqs, rec.plan.speed(omega), rec.C_link)
    return [spla.splu(Z).solve(P) for Z in matrices]


def link_torus_model(model) -> qp.TorusModel:
    """The :class:`~nlgrd.nonlinear.hb.quasi_periodic.TorusModel` of a link model.

    Parameters
    ----------
    model : LinkModel
        From :func:`nlgrd.nonlinear.models.link_model.build_link_model` (period 1).

    Returns
    -------
    TorusModel
        κ(Ω) = (Pᵀ Z(Ω)⁻¹ P)⁻¹ by a sparse LU of the full model per frequency, at the
        speed of ω₁; the periodic κ_k, F_k and the link laws of ``model.reduced``.

    Raises
    ------
    ModelError
        When the model is of period ν > 1.
    """
    if model.period != 1:
        raise ModelError("period", f"the torus balance needs a period-1 model, got period {model.period}")
    P = model.receptance.P

    def kappa_at(freqs: NDArray, omega: float) -> NDArray:
        out = np.empty((len(freqs), P.shape[1], P.shape[1]), dtype=complex)
        for i, x in enumerate(_receptances(model, freqs, omega)):
            out[i] = np.linalg.inv(P.T @ x)
        return out

    def kappa_slope_at(freqs: NDArray, omega: float) -> tuple[NDArray, NDArray]:
        rec = model.receptance
        return kappa_and_slope(rec.model, P, freqs, rec.plan.speed(omega), extra=rec.C_link)

    red = model.reduced
    return qp.TorusModel(kappa_at, red.kappa, red.force, red.nonlinearities, kappa_slope_at=kappa_slope_at)


def torus_link_bearings(model, sol: qp.TorusSolution, n_samples: tuple[int, int] = SAMPLES) -> dict:
    """Every linear bearing's outputs over a torus of a link model (module docstring):
    the fields of :func:`nlgrd.nonlinear.tracing.torus_outputs.torus_bearing_statistics`.

    Parameters
    ----------
    model : LinkModel
        The model solved.
    sol : TorusSolution
        A converged torus.
    n_samples : tuple of int
        Samples along θ₁ and θ₂ [-].

    Returns
    -------
    dict of str to ndarray (n_bearings,)
        [m] and [N].
    """
    system, rec = model.system, model.receptance
    g, w = sol.grid, sol.omega
    H1, d = g.H1, rec.n_coords
    dofs = bearing_node_dofs(system)
    Y = sol.Y
    Yp = Y[:, : H1 + 1]  # the k₂ = 0 row: the periodic recovery, with the external forces
    F = np.asarray(model.reduced.force(w, H1), dtype=complex).reshape(H1 + 1, d)
    kap = np.asarray(model.reduced.kappa(w, H1), dtype=complex).reshape(H1 + 1, d, d)
    G = F - np.einsum("kij,jk->ki", kap, Yp)
    Q = np.zeros((g.n_terms, dofs.size), dtype=complex)
    q = rec.recover(w, H1, complex_to_real(Yp), complex_to_real(G.T), dofs)
    Q[: H1 + 1] = real_to_complex(q).T
    freqs = g.k1 * w + g.k2 * sol.secondary
    for i, x in zip(range(H1 + 1, g.n_terms), _receptances(model, freqs[H1 + 1 :], w), strict=True):
        Q[i] = x[dofs] @ np.linalg.solve(rec.P.T @ x, Y[:, i])
    Fb = bearing_force_harmonics(system, Q, freqs, rec.plan.speed(w))
    return torus_bearing_statistics(Q, Fb, g, n_samples)


def torus_link_columns(
    model,
    sol: qp.TorusSolution,
    n_samples: tuple[int, int] = SAMPLES,
    bearings: dict | None = None,
    with_bearings: bool = True,
    known: dict | None = None,
) -> dict:
    """Every link's outputs over a torus, in the columns of a link sweep
    (``<link>.<quantity> [unit]``, :func:`nlgrd.nonlinear.results.link_results.output_names`):
    a gear mesh's mean, RMS and peak-to-peak DTE, largest and smallest force, DSLR,
    contact-loss fraction and back contact
    (:func:`~nlgrd.nonlinear.tracing.torus_outputs.torus_outputs` on its coordinate), a
    bearing clearance's contact fraction, largest contact force and radial displacement,
    then every linear bearing's (:func:`torus_link_bearings`); NaN for a link of another
    kind.

    Parameters
    ----------
    model : LinkModel
        The model solved.
    sol : TorusSolution
        A converged torus.
    n_samples : tuple of int
        Samples along θ₁ and θ₂ [-].
    bearings : dict, optional
        :func:`torus_link_bearings` of ``sol``, if computed already.
    with_bearings : bool
        Also the linear bearings' columns (False: the links' only, as the convergence
        estimate compares them; no recovery at every frequency).
    known : dict of int to ndarray, optional
        :func:`~nlgrd.nonlinear.tracing.torus_outputs.torus_outputs` of ``sol`` on these
        ``n_samples`` by a mesh's first coordinate, if computed already.

    Returns
    -------
    dict of str to float
        SI, as the link sweep's columns.
    """
    g = sol.grid
    fine = g.refined(n_samples)
    names = list(TORUS_OUTPUTS)
    out: dict[str, float] = {}
    for link, sl in zip(model.links, model.receptance.slices, strict=True):
        n = link.name
        if hasattr(link, "mesh"):
            o = (known or {}).get(sl.start)
            o = torus_outputs(sol, link.mesh, n_samples, coord=sl.start) if o is None else o
            for q, key in (
                ("dte_mean [m]", "dte_mean"),
                ("dte_rms [m]", "dte_rms"),
                ("dte_p2p [m]", "dte_p2p"),
                ("force_max [N]", "force_max"),
                ("force_min [N]", "force_min"),
                ("dslr [-]", "dslr"),
                ("contact_loss_fraction [-]", "contact_loss_fraction"),
            ):
                out[f"{n}.{q}"] = float(o[names.index(key)])
            out[f"{n}.back_contact"] = float(torus_back_contact(sol, link.mesh, n_samples, coord=sl.start))
        elif hasattr(link, "clearance"):
            u = fine.samples(sol.Y[sl])
            r = np.hypot(u[0], u[1])
            f = link.law(tuple(range(sl.stop - sl.start))).force_at(u)
            out[f"{n}.contact_fraction [-]"] = float(np.mean(r > link.clearance))
            out[f"{n}.force_max [N]"] = float(np.max(np.hypot(f[0], f[1])))
            out[f"{n}.displacement_max [m]"] = float(np.max(r))
        else:
            out.update({f"{n}.{q}": np.nan for q in link.metrics(np.zeros((link.n_coords, 3)), 1.0)})
    if with_bearings and model.system.bearings:
        b = torus_link_bearings(model, sol, n_samples) if bearings is None else bearings
        for j, name in enumerate(bearing_names(model.system)):
            for q in BEARING_OUTPUTS:
                field = q.split(" ")[0]
                out[f"{name}.{q}"] = float(b[field][j])
    return out


class LinkTorus:
    """What :func:`~nlgrd.nonlinear.tracing.torus_sweep.torus_sweep` and
    :func:`~nlgrd.nonlinear.tracing.torus_sweep.converged_tori` need of a link model, one
    mesh too: the torus model, the periodic model, the outputs and the convergence
    estimate. The sweep's own
    metrics (``TORUS_OUTPUTS``) are those of the law its periodic points report
    (``model.reduced.metrics``: the first gear mesh; NaN without one); the convergence
    estimate compares every link's checked outputs (its ``converged_outputs``, those the
    periodic choice of H compares) and ω₂.

    Parameters
    ----------
    model : LinkModel
        From :func:`nlgrd.nonlinear.models.link_model.build_link_model` (period 1).

    Attributes
    ----------
    torus_model : TorusModel
        :func:`link_torus_model`.
    reduced : ReducedModel
        The periodic model.
    bearing_names : list of str
        The linear bearings' names, as the link sweep's columns.
    mesh_names : tuple of str
        Every gear mesh's link name, in the model's order (the first: the metrics law's).
    """

    def __init__(self, model):
        self.model = model
        self.torus_model = link_torus_model(model)
        self.reduced = model.reduced
        self.bearing_names = bearing_names(model.system)
        self._mesh = getattr(model.reduced.metrics, "mesh", None)
        self._meshes = [
            (lk.name, lk.mesh, sl.start)
            for lk, sl in zip(model.links, model.receptance.slices, strict=True)
            if hasattr(lk, "mesh")
        ]
        self.mesh_names = tuple(name for name, _, _ in self._meshes)
        picks = [getattr(lk, "converged_outputs", None) or () for lk in model.links]
        self._checked = [f"{lk.name}.{q}" for lk, qs in zip(model.links, picks, strict=True) for q in qs]
        scales = model.reduced.output_scales
        self._scales = np.zeros(len(self._checked)) if scales is None else np.asarray(scales, dtype=float)
        if self._scales.size != len(self._checked):
            self._scales = np.zeros(len(self._checked))

    def prepare(self, max_frequency: float) -> None:
        """The model's receptance built for excitations up to ``max_frequency`` [rad/s]
        (:meth:`~nlgrd.nonlinear.reduction.link_reduction.LinkReceptance.prepare`: a modal
        basis; nothing on a dense one)."""
        self.model.receptance.prepare(max_frequency)

    def omegas(self, rpm: NDArray) -> NDArray:
        """Base frequencies [rad/s] of reference shaft speeds ``rpm`` [rpm]."""
        plan = self.model.receptance.plan
        return np.asarray(rpm, dtype=float) * 2 * np.pi / 60 / plan.speed_per_base

    def rpm(self, omegas: NDArray) -> NDArray:
        """Reference shaft speeds [rpm] of base frequencies ``omegas`` [rad/s]."""
        plan = self.model.receptance.plan
        return np.asarray(omegas, dtype=float) * plan.speed_per_base * 60 / (2 * np.pi)

    def outputs(self, sol: qp.TorusSolution) -> NDArray:
        """The sweep's metrics law's :func:`torus_outputs` (SI); NaN but ω₂ without one."""
        if self._mesh is None:
            out = np.full(len(TORUS_OUTPUTS), np.nan)
            out[-1] = sol.secondary if sol.converged else np.nan
            return out
        return torus_outputs(sol, self._mesh, coord=self._mesh.coord)

    def mesh_outputs(self, sol: qp.TorusSolution, first: NDArray | None = None) -> NDArray:
        """:func:`torus_outputs` of every gear mesh (SI), in :attr:`mesh_names`' order.

        Parameters
        ----------
        sol : TorusSolution
            A torus.
        first : ndarray, optional
            :meth:`outputs` of ``sol`` (the first mesh's), if computed already.

        Returns
        -------
        ndarray (len(mesh_names), len(TORUS_OUTPUTS))
        """
        out = np.full((len(self._meshes), len(TORUS_OUTPUTS)), np.nan)
        for j, (_, mesh, coord) in enumerate(self._meshes):
            reuse = j == 0 and first is not None
            out[j] = first if reuse else torus_outputs(sol, mesh, SAMPLES, coord=coord)
        return out

    def _values(self, sol: qp.TorusSolution, outputs: NDArray) -> NDArray:
        """The checked link outputs and ω₂ of ``sol`` (``outputs``: its :meth:`outputs`)."""
        known = None if self._mesh is None else {int(self._mesh.coord): outputs}
        cols = torus_link_columns(self.model, sol, SAMPLES, with_bearings=False, known=known)
        return np.array([cols[c] for c in self._checked] + [sol.secondary])

    def change(
        self, outputs: NDArray, sol: qp.TorusSolution, fine: qp.TorusSolution
    ) -> tuple[NDArray, float]:
        """The relative change of the metrics law's checked outputs from ``sol`` to
        ``fine`` (NaN without a mesh) and the convergence estimate: the largest relative
        change of every link's checked outputs and ω₂, each measured against the larger
        of its value at ``fine`` and :data:`FLOOR` x its physical scale (an output zero at
        both changes by 0) [-]."""
        idx = [list(TORUS_OUTPUTS).index(c) for c in CHECKED]
        fine_outputs = self.outputs(fine)
        ch = fine_outputs[idx] / outputs[idx] - 1
        a, b = self._values(sol, outputs), self._values(fine, fine_outputs)
        scale = np.append(FLOOR * self._scales, 0.0)
        den = np.maximum(np.abs(b), scale)
        diff = np.abs(b - a)
        rel = np.where(diff == 0, 0.0, diff / np.where(den > 0, den, 1.0))
        return ch, float(np.max(rel))

    def mesh_change(self, mesh_outputs: NDArray, fine: qp.TorusSolution) -> NDArray:
        """The relative change of every gear mesh's :data:`CHECKED` outputs from a torus
        (its :meth:`mesh_outputs`) to ``fine`` [-], (len(mesh_names), len(CHECKED)); the
        first mesh's is :meth:`change`'s first value."""
        idx = [list(TORUS_OUTPUTS).index(c) for c in CHECKED]
        big = self.mesh_outputs(fine, self.outputs(fine) if self._mesh is not None else None)
        return big[:, idx] / mesh_outputs[:, idx] - 1

    def bearing_force_max(self, sol: qp.TorusSolution) -> NDArray:
        """Each linear bearing's largest radial force over the torus [N]."""
        if not self.bearing_names:
            return np.zeros(0)
        return torus_link_bearings(self.model, sol)["force_max"]

    def answer(self, sol: qp.TorusSolution, outputs: NDArray) -> tuple[dict, dict, dict]:
        """A torus's answer to a sweep point: the metrics law's :data:`TORUS_OUTPUTS` with
        ``back_contact``, the linear bearings' outputs and the link sweep's columns
        (:func:`torus_link_columns`)."""
        out = dict(zip(TORUS_OUTPUTS, outputs, strict=True))
        out["back_contact"] = (
            torus_back_contact(sol, self._mesh, coord=self._mesh.coord) if self._mesh is not None else False
        )
        bearings = torus_link_bearings(self.model, sol) if self.bearing_names else {}
        return out, bearings, torus_link_columns(self.model, sol, bearings=bearings or None)

"""Linear frequency response (receptance) between DOFs, and static deflection."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import pandas as pd
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from numpy.typing import NDArray

from nlgrd.errors import ModelError
from nlgrd.rotor.assembly import LinearModel, assemble
from nlgrd.rotor.rigid_body import check_balanced, rigid_body_modes
from nlgrd.rotor.system import RotorSystem
from nlgrd.units import um

DofSpec = int | tuple[int | str, int, str]


def _as_model(system_or_model: RotorSystem | LinearModel) -> LinearModel:
    if isinstance(system_or_model, LinearModel):
        return system_or_model
    return assemble(system_or_model)


def _resolve(model: LinearModel, dofs: Sequence[DofSpec], key: str) -> tuple[NDArray, list[str]]:
    """Global indices and names of DOFs given as indices or (shaft, node, dof) tuples."""
    idx, names = [], []
    for d in dofs:
        if isinstance(d, (int, np.integer)):
            if not 0 <= d < model.n_dofs:
                raise ModelError(key, f"DOF index {d} out of range 0..{model.n_dofs - 1}")
            idx.append(int(d))
            names.append(model.system.dofs.name(d) if model.system is not None else f"dof {d}")
        else:
            if model.system is None:
                raise ModelError(key, "named DOFs need a model built from a RotorSystem")
            i = model.system.dofs.index(*d)
            idx.append(i)
            names.append(model.system.dofs.name(i))
    return np.array(idx, dtype=int), names


@dataclass(frozen=True)
class FrequencyResponse:
    """Receptance matrix over frequency.

    Attributes
    ----------
    omega : ndarray
        Excitation frequencies [rad/s].
    H : ndarray, (n_freq, n_out, n_in), complex
        Receptance [m/N or rad/(N m)]: response amplitude per unit harmonic force.
    inputs, outputs : list of str
        DOF names.
    speed : float
        Reference speed [rad/s].
    """

    omega: NDArray
    H: NDArray
    inputs: list[str]
    outputs: list[str]
    speed: float

    def to_frame(self) -> pd.DataFrame:
        """Tidy table: frequency, output, input, magnitude, phase, real, imaginary parts."""
        nf, no, ni = self.H.shape
        f = np.repeat(self.omega / (2 * np.pi), no * ni)
        H = self.H.reshape(nf, -1).ravel()
        return pd.DataFrame(
            {
                "frequency [Hz]": f,
                "output": np.tile(np.repeat(self.outputs, ni), nf),
                "input": np.tile(np.tile(self.inputs, no), nf),
                "magnitude [m/N]": np.abs(H),
                "phase [deg]": np.degrees(np.angle(H)),
                "real [m/N]": H.real,
                "imag [m/N]": H.imag,
            }
        )

    def plot(self, output: int = 0, input: int = 0, ax=None):
        """Bode magnitude plot of one entry; see :func:`nlgrd.plotting.rotor.plot_frequency_response`."""
        from nlgrd.plotting.rotor import plot_frequency_response

        return plot_frequency_response(self, output, input, ax=ax)


def frequency_response(
    system: RotorSystem | LinearModel,
    omega: NDArray,
    inputs: Sequence[DofSpec],
    outputs: Sequence[DofSpec] | None = None,
    speed: float = 0.0,
) -> FrequencyResponse:
    """Receptance H(ω) = Z(ω)⁻¹ between ``inputs`` and ``outputs``.

    Z(ω) = K - ω² M + i ω (C + C_i + Ω G) + hysteretic; each frequency is one sparse
    LU factorisation solved for all inputs at once.

    Parameters
    ----------
    system : RotorSystem or LinearModel
        The model; a RotorSystem is assembled with its gear meshes at their average
        stiffness.
    omega : array_like
        Frequencies [rad/s].
    inputs, outputs : sequence
        DOFs as global indices or ``(shaft, node, dof)`` tuples, e.g. ``(0, 3, "uy")``.
        Outputs default to the inputs.
    speed : float
        Reference speed [rad/s].

    Returns
    -------
    FrequencyResponse
        Receptances H of shape (n_freq, n_out, n_in) [m/N or rad/(N m)].

    Raises
    ------
    ModelError
        When a frequency is not finite or a DOF does not exist.
    """
    model = _as_model(system)
    omega = np.atleast_1d(np.asarray(omega, dtype=float))
    if not np.all(np.isfinite(omega)):
        raise ModelError("omega", "frequencies must be finite")
    i_in, n_in = _resolve(model, inputs, "inputs")
    i_out, n_out = _resolve(model, outputs if outputs is not None else inputs, "outputs")
    n = model.n_dofs
    rhs = np.zeros((n, len(i_in)), dtype=complex)
    rhs[i_in, np.arange(len(i_in))] = 1.0
    H = np.empty((len(omega), len(i_out), len(i_in)), dtype=complex)
    for j, w in enumerate(omega):
        lu = spla.splu(model.dynamic_stiffness(w, speed))
        H[j] = lu.solve(rhs)[i_out]
    return FrequencyResponse(omega, H, n_in, n_out, float(speed))


@dataclass(frozen=True)
class StaticResult:
    """Static deflection under constant loads.

    Attributes
    ----------
    q : ndarray, (n_dofs,)
        Displacements of all DOFs [m, rad].
    model : LinearModel
        The model solved.
    """

    q: NDArray
    model: LinearModel

    def to_frame(self) -> pd.DataFrame:
        """One row per node: its shaft and node, its position ``x [m]``, the displacements
        ``ux``, ``uy``, ``uz`` [um] and the rotations ``θx``, ``θy``, ``θz`` [rad]; a model of
        matrices (no rotor): ``dof`` and ``value [m or rad]``."""
        if self.model.system is None:
            return pd.DataFrame({"dof": np.arange(len(self.q)), "value [m or rad]": self.q})
        rows = []
        dm = self.model.system.dofs
        for s, shaft in enumerate(self.model.system.shafts):
            for node, x in enumerate(shaft.node_positions):
                v = self.q[dm.node_dofs(s, node)]
                rows.append(
                    {
                        "shaft": s,
                        "node": node,
                        "x [m]": x,
                        "ux [um]": um(v[0]),
                        "uy [um]": um(v[1]),
                        "uz [um]": um(v[2]),
                        "θx [rad]": v[3],
                        "θy [rad]": v[4],
                        "θz [rad]": v[5],
                    }
                )
        return pd.DataFrame(rows)

    def plot(self, ax=None):
        """Deflection along the shafts; see :func:`nlgrd.plotting.rotor.plot_static`."""
        from nlgrd.plotting.rotor import plot_static

        return plot_static(self, ax=ax)


def static_deflection(
    system: RotorSystem | LinearModel,
    loads: NDArray | dict[tuple[int | str, int, str], float],
    speed: float = 0.0,
) -> StaticResult:
    """Static deflection K q = f, with rigid-body modes handled.

    Loads must not have a net component on a rigid-body mode (e.g. an unbalanced torque
    on a free drive train); the returned deflection is M-orthogonal to those modes.

    Parameters
    ----------
    system : RotorSystem or LinearModel
        The model; a RotorSystem is assembled with its gear meshes at their average
        stiffness.
    loads : ndarray or dict
        Force vector (n_dofs,) [N, N m] or ``{(shaft, node, dof): value}``.
    speed : float
        Reference speed [rad/s] (circulatory terms).

    Returns
    -------
    StaticResult
        The deflection q [m, rad].

    Raises
    ------
    ModelError
        When the loads have the wrong length, are not finite or are not balanced.
    """
    model = _as_model(system)
    n = model.n_dofs
    if isinstance(loads, dict):
        f = np.zeros(n)
        for key, val in loads.items():
            f[model.system.dofs.index(*key)] += val
    else:
        f = np.asarray(loads, dtype=float)
        if f.shape != (n,):
            raise ModelError("loads", f"load vector must have {n} entries, got shape {f.shape}")
    if not np.all(np.isfinite(f)):
        raise ModelError("loads", "loads must be finite")
    K = model.stiffness(speed)
    R = rigid_body_modes(model.K, model.M)
    if R.shape[1]:
        check_balanced(R, f, "loads")
        MR = model.M @ R
        K = (K + sp.csc_matrix(MR @ MR.T) * float(np.max(np.abs(K.diagonal())))).tocsc()
    q = spla.spsolve(K.tocsc(), f)
    return StaticResult(np.asarray(q), model)

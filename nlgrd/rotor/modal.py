"""Modal analysis of the linear system: undamped and damped complex modes, Campbell diagram.

The damped (and gyroscopic) eigenproblem is solved in first-order form,

    [[0, I], [-K, -D]] z = λ [[I, 0], [0, M]] z,   z = (q, λ q),

with D = C + C_i + Ω G and K including the circulatory stiffness (Friswell et al.,
Dynamics of Rotating Machines, 2010, §3.6). Internal hysteretic damping has no
first-order form and is left out of modal analysis (it acts in frequency response).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pandas as pd
import scipy.linalg as sla
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from numpy.typing import NDArray

from nlgrd.rotor.assembly import LinearModel, assemble
from nlgrd.rotor.rigid_body import rigid_body_modes
from nlgrd.rotor.system import DOFS_PER_NODE, RotorSystem

#: Models with more DOFs than this use sparse shift-invert eigensolvers.
DENSE_LIMIT = 1500
#: Eigenvalues with Im λ <= OVERDAMPED_RTOL |λ| are overdamped (non-oscillatory): not listed.
#: Real eigenvalues of large modulus come out of eig with Im λ ~ 1e-9 |λ| (rounding), which
#: would list them as "modes" of 0.002-2 Hz; a real mode this close to critical damping
#: (ζ > 1 - 5e-13) has no resonance to show.
OVERDAMPED_RTOL = 1e-6


def _as_model(system_or_model: RotorSystem | LinearModel) -> LinearModel:
    if isinstance(system_or_model, LinearModel):
        return system_or_model
    return assemble(system_or_model)


def _rigid_fraction(model: LinearModel, R: NDArray, shapes: NDArray) -> NDArray:
    """Fraction of each shape's M-norm² in span(R) (R M-orthonormal): ~1 rigid, ~0 flexible."""
    if R.shape[1] == 0:
        return np.zeros(shapes.shape[1])
    Mq = model.M @ shapes
    total = np.real(np.sum(np.conj(shapes) * Mq, axis=0))
    total[total == 0] = 1.0
    return np.sum(np.abs(R.T @ Mq) ** 2, axis=0) / total


def _kind_fractions(model: LinearModel, shapes: NDArray) -> dict[str, NDArray]:
    """Kinetic-energy fractions of each mode in axial, lateral and torsional DOFs."""
    n = model.n_dofs
    e = np.real(np.conj(shapes) * (model.M @ shapes))
    total = np.sum(e, axis=0)
    total[total == 0] = 1.0
    out = {}
    for kind, local in (("axial", [0]), ("lateral", [1, 2, 4, 5]), ("torsional", [3])):
        mask = np.zeros(n, dtype=bool)
        for d in local:
            mask[d::DOFS_PER_NODE] = True
        out[kind] = np.sum(e[mask], axis=0) / total
    return out


def _whirl_index(model: LinearModel, shapes: NDArray) -> NDArray:
    """Whirl index per mode in [-1, 1]: +1 circular forward, -1 circular backward.

    For node motion y = Re(Y e^{iωt}), z = Re(Z e^{iωt}) the orbit turns from y to z
    (positive about x) when -Im(conj(Y) Z) > 0; it is forward when that sense agrees
    with the shaft's own spin (sign of its speed ratio). Weighted by orbit size.
    """
    n = model.n_dofs
    sense = np.ones(n // DOFS_PER_NODE)
    if model.system is not None:
        dm = model.system.dofs
        for s, shaft in enumerate(model.system.shafts):
            start = dm.first_node[s]
            sense[start : start + shaft.n_nodes] = 1.0 if shaft.speed_ratio >= 0 else -1.0
    Y = shapes[1::DOFS_PER_NODE]
    Z = shapes[2::DOFS_PER_NODE]
    num = np.sum(sense[:, None] * (-np.imag(np.conj(Y) * Z)), axis=0)
    den = np.sum((np.abs(Y) ** 2 + np.abs(Z) ** 2) / 2, axis=0)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(den > 0, num / np.where(den > 0, den, 1.0), 0.0)


def _normalise(shapes: NDArray) -> NDArray:
    """Scale each mode so its largest entry is real and equal to 1."""
    idx = np.argmax(np.abs(shapes), axis=0)
    peak = shapes[idx, np.arange(shapes.shape[1])]
    peak[peak == 0] = 1.0
    return shapes / peak


@dataclass(frozen=True)
class ModalResult:
    """Modes of the linear system at one speed.

    Attributes
    ----------
    speed : float
        Reference (pinion) speed [rad/s].
    eigenvalues : ndarray of complex
        λ = -ζ ω_n + i ω_d [1/s], sorted by damped frequency.
    shapes : ndarray, (n_dofs, n_modes)
        Mode shapes (displacement part), largest entry 1.
    fractions : dict of ndarray
        Kinetic-energy fractions in 'axial', 'lateral', 'torsional' DOFs.
    whirl_index : ndarray
        +1 forward circular whirl, -1 backward, 0 planar or not lateral.
    n_rigid_body : int
        Number of rigid-body modes found (left out of the arrays).
    damped : bool
        Whether damping and gyroscopic terms were included.
    model : LinearModel or None
        The model analysed.
    """

    speed: float
    eigenvalues: NDArray
    shapes: NDArray
    fractions: dict[str, NDArray]
    whirl_index: NDArray
    n_rigid_body: int
    damped: bool
    model: LinearModel | None = field(default=None, repr=False, compare=False)

    @property
    def natural_frequencies(self) -> NDArray:
        """Undamped natural frequencies |λ| / 2π [Hz]."""
        return np.abs(self.eigenvalues) / (2 * np.pi)

    @property
    def damped_frequencies(self) -> NDArray:
        """Damped natural frequencies Im λ / 2π [Hz]."""
        return np.imag(self.eigenvalues) / (2 * np.pi)

    @property
    def damping_ratios(self) -> NDArray:
        """Damping ratios ζ = -Re λ / |λ| [-] (negative means unstable)."""
        return -np.real(self.eigenvalues) / np.abs(self.eigenvalues)

    @property
    def kinds(self) -> list[str]:
        """'lateral', 'torsional', 'axial' (>= 70 % of kinetic energy) or 'coupled'."""
        out = []
        for i in range(len(self.eigenvalues)):
            f = {k: v[i] for k, v in self.fractions.items()}
            k = max(f, key=f.get)
            out.append(k if f[k] >= 0.7 else "coupled")
        return out

    @property
    def whirl(self) -> list[str]:
        """'forward', 'backward' or 'planar' for modes with lateral motion, else '-'."""
        out = []
        for i, w in enumerate(self.whirl_index):
            if self.fractions["lateral"][i] < 0.05:
                out.append("-")
            elif w > 0.05:
                out.append("forward")
            elif w < -0.05:
                out.append("backward")
            else:
                out.append("planar")
        return out

    def to_frame(self) -> pd.DataFrame:
        """One row per mode, units in the column names."""
        return pd.DataFrame(
            {
                "mode": np.arange(1, len(self.eigenvalues) + 1),
                "natural_frequency [Hz]": self.natural_frequencies,
                "damped_frequency [Hz]": self.damped_frequencies,
                "damping_ratio [-]": self.damping_ratios,
                "kind": self.kinds,
                "whirl": self.whirl,
                "lateral_energy [-]": self.fractions["lateral"],
                "torsional_energy [-]": self.fractions["torsional"],
                "axial_energy [-]": self.fractions["axial"],
                "speed [rpm]": self.speed * 30 / np.pi,
            }
        )

    def plot(self, mode: int = 0, ax=None):
        """Plot one mode shape (0-based); see :func:`nlgrd.plotting.rotor.plot_mode_shape`."""
        from nlgrd.plotting.rotor import plot_mode_shape

        return plot_mode_shape(self, mode, ax=ax)


def modal_analysis(
    system: RotorSystem | LinearModel,
    speed: float = 0.0,
    n_modes: int = 20,
    damped: bool = True,
) -> ModalResult:
    """Natural frequencies, damping ratios and mode shapes at reference speed ``speed``.

    Parameters
    ----------
    system : RotorSystem or LinearModel
        The model; gear meshes enter at their average stiffness.
    speed : float
        Reference (pinion) speed Ω [rad/s]; scales gyroscopic and circulatory terms.
    n_modes : int
        Number of flexible modes to return (rigid-body modes are counted, not returned).
    damped : bool
        True: complex modes with damping and gyroscopics (first-order form).
        False: real modes of K φ = ω² M φ.

    Returns
    -------
    ModalResult
        The flexible modes, sorted by damped frequency.
    """
    model = _as_model(system)
    n = model.n_dofs
    K = model.stiffness(speed)
    M = model.M
    R = rigid_body_modes(model.K, M)
    n_rigid = R.shape[1]
    want = min(n_modes + 12 + n_rigid, n - 1)
    if not damped:
        if n <= DENSE_LIMIT:
            w2, vec = sla.eigh(K.toarray(), M.toarray())
        else:
            w2, vec = spla.eigsh(K, k=want, M=M, sigma=-1.0, v0=np.full(n, 1.0 / np.sqrt(n)))
        order = np.argsort(w2)
        w2, vec = w2[order], vec[:, order]
        flexible = _rigid_fraction(model, R, vec) < 0.5
        w = np.sqrt(np.clip(w2[flexible], 0.0, None))
        lam = 1j * w[:n_modes]
        shapes = vec[:, flexible][:, :n_modes].astype(complex)
    else:
        D = model.damping(speed)
        I = sp.identity(n, format="csc")
        A = sp.bmat([[None, I], [-K, -D]], format="csc")
        B = sp.bmat([[I, None], [None, M]], format="csc")
        if n <= DENSE_LIMIT:
            lam_all, vec_all = sla.eig(A.toarray(), B.toarray())
        else:
            v0 = np.full(2 * n, 1.0 / np.sqrt(2 * n))
            lam_all, vec_all = spla.eigs(A, k=2 * want, M=B, sigma=-1.0, v0=v0)
        finite = np.isfinite(lam_all)
        lam_all, vec_all = lam_all[finite], vec_all[:n, finite]
        flexible = _rigid_fraction(model, R, vec_all) < 0.5
        osc = flexible & (np.imag(lam_all) > OVERDAMPED_RTOL * np.abs(lam_all))
        lam, vec = lam_all[osc], vec_all[:, osc]
        order = np.argsort(np.imag(lam))
        lam, shapes = lam[order][:n_modes], vec[:, order][:, :n_modes]
    shapes = _normalise(shapes)
    return ModalResult(
        speed=float(speed),
        eigenvalues=lam,
        shapes=shapes,
        fractions=_kind_fractions(model, shapes),
        whirl_index=_whirl_index(model, shapes),
        n_rigid_body=n_rigid,
        damped=damped,
        model=model,
    )


@dataclass(frozen=True)
class CampbellResult:
    """Damped natural frequencies against speed, with critical speeds.

    Attributes
    ----------
    speeds : ndarray
        Reference speeds [rad/s].
    frequencies : ndarray, (n_speeds, n_modes)
        Damped natural frequencies [Hz], sorted at each speed.
    damping_ratios : ndarray, (n_speeds, n_modes)
        Modal damping ratios ζ [-].
    whirl : ndarray of str, (n_speeds, n_modes)
        'forward', 'backward', 'planar' or '-' (see :attr:`ModalResult.whirl`).
    kinds : ndarray of str, (n_speeds, n_modes)
        'lateral', 'torsional', 'axial' or 'coupled' (see :attr:`ModalResult.kinds`).
    orders : dict
        Excitation orders: label -> multiple of the reference speed.
    critical_speeds : list of dict
        Crossings of each mode curve with each order line: 'order', 'mode',
        'speed [rpm]', 'frequency [Hz]'.
    """

    speeds: NDArray
    frequencies: NDArray
    damping_ratios: NDArray
    whirl: NDArray
    kinds: NDArray
    orders: dict[str, float]
    critical_speeds: list[dict]

    def to_frame(self) -> pd.DataFrame:
        """Tidy table: one row per speed and mode."""
        ns, nm = self.frequencies.shape
        return pd.DataFrame(
            {
                "speed [rpm]": np.repeat(self.speeds * 30 / np.pi, nm),
                "mode": np.tile(np.arange(1, nm + 1), ns),
                "damped_frequency [Hz]": self.frequencies.ravel(),
                "damping_ratio [-]": self.damping_ratios.ravel(),
                "whirl": self.whirl.ravel(),
                "kind": self.kinds.ravel(),
            }
        )

    def critical_frame(self) -> pd.DataFrame:
        """Table of critical speeds."""
        return pd.DataFrame(self.critical_speeds, columns=["order", "mode", "speed [rpm]", "frequency [Hz]"])

    def plot(self, ax=None):
        """Campbell diagram; see :func:`nlgrd.plotting.rotor.plot_campbell`."""
        from nlgrd.plotting.rotor import plot_campbell

        return plot_campbell(self, ax=ax)


def campbell(
    system: RotorSystem | LinearModel,
    speeds: NDArray,
    n_modes: int = 10,
    orders: dict[str, float] | None = None,
    progress=None,
) -> CampbellResult:
    """Campbell diagram over reference speeds ``speeds`` [rad/s].

    Parameters
    ----------
    system : RotorSystem or LinearModel
        The model; gear meshes enter at their average stiffness.
    speeds : array_like
        Reference (pinion) speeds Ω [rad/s].
    n_modes : int
        Number of flexible modes followed at each speed.
    orders : dict, optional
        Excitation orders as multiples of the reference speed, e.g.
        ``{"1x": 1, "mesh": 25}``; default ``{"1x": 1}``.
    progress : callable, optional
        Called as ``progress(i, n)`` after each speed (i = 1 .. n).

    Returns
    -------
    CampbellResult
        Damped frequencies [Hz] per speed and mode, with the critical speeds.

    Notes
    -----
    Critical speeds are where a mode's damped frequency equals order x speed / 2π,
    found by linear interpolation between neighbouring speeds.
    """
    model = _as_model(system)
    speeds = np.asarray(speeds, dtype=float)
    orders = dict(orders or {"1x": 1.0})
    F = np.full((len(speeds), n_modes), np.nan)
    Z = np.full_like(F, np.nan)
    W = np.full(F.shape, "", dtype=object)
    Kd = np.full(F.shape, "", dtype=object)
    for i, s in enumerate(speeds):
        res = modal_analysis(model, speed=s, n_modes=n_modes)
        m = len(res.eigenvalues)
        F[i, :m] = res.damped_frequencies
        Z[i, :m] = res.damping_ratios
        W[i, :m] = res.whirl
        Kd[i, :m] = res.kinds
        if progress:
            progress(i + 1, len(speeds))
    crit = []
    for label, order in orders.items():
        line = order * speeds / (2 * np.pi)
        for j in range(n_modes):
            g = F[:, j] - line
            for i in range(len(speeds) - 1):
                if np.isfinite(g[i]) and np.isfinite(g[i + 1]) and g[i] * g[i + 1] < 0:
                    t = g[i] / (g[i] - g[i + 1])
                    sc = speeds[i] + t * (speeds[i + 1] - speeds[i])
                    crit.append(
                        {
                            "order": label,
                            "mode": j + 1,
                            "speed [rpm]": sc * 30 / np.pi,
                            "frequency [Hz]": order * sc / (2 * np.pi),
                        }
                    )
    return CampbellResult(speeds, F, Z, W, Kd, orders, crit)


def gear_pair_mode(system: RotorSystem, speed: float = 0.0, n_modes: int = 40) -> tuple[float, float]:
    """Natural frequency [Hz] of the gear-pair mode and its mesh strain-energy fraction.

    The mode of the linear system (mesh at k_h) whose share of strain energy in the mesh
    spring, k_h |wᵀφ|² / φᴴ K φ, is largest: where the mesh frequency meets it, the main
    resonance of the gear dynamics lies.

    Parameters
    ----------
    system : RotorSystem
        With at least one gear pair (the first mesh is used).
    speed : float
        Reference shaft speed Ω of the modal analysis [rad/s].
    n_modes : int
        Number of modes computed.

    Returns
    -------
    frequency : float
        Undamped natural frequency of the gear-pair mode [Hz].
    fraction : float
        Its share of strain energy in the mesh spring [-].
    """
    lm = assemble(system)
    res = modal_analysis(lm, speed=speed, n_modes=n_modes, damped=False)
    link = lm.meshes[0]
    phi = res.shapes
    strain = np.real(np.einsum("ij,ij->j", np.conj(phi), lm.stiffness(speed) @ phi))
    frac = link.stiffness * np.abs(link.w @ phi) ** 2 / strain
    j = int(np.argmax(frac))
    return float(res.natural_frequencies[j]), float(frac[j])

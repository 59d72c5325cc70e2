"""Load sharing and loaded static transmission error (LSTE) of a spur gear pair.

Every tooth pair j in contact is a spring along the line of action (LOA) with the
compliance c_j(s) of :mod:`nlgrd.gear.tooth_stiffness` at its contact position s, and an
initial separation σ_j: the gap left between its flanks when the gears are turned
rigidly into contact, made of the tip reliefs and of the gear errors. Under the mesh
load W (along the LOA) the gears approach each other by δ, common to all pairs
(compatibility), and each pair carries

    F_j = max(0, (δ - σ_j) / c_j),      Σ_j F_j(δ) = W

(Tavakoli & Houser 1986, J. Mech. Trans. Autom. Des. 108:86; Özgüven & Houser 1988,
J. Sound Vib. 125:71, for the LSTE as the mesh excitation; Lin, Oswald & Townsend
1994, Mech. Mach. Theory 29:1115, for linear and parabolic tip relief). Σ F_j(δ) is
continuous, piecewise linear and increasing in δ, so the root is found exactly: with
the pairs sorted by separation, the first n carry load where
δ_n = (W + Σ_{j<=n} σ_j/c_j) / Σ_{j<=n} 1/c_j lies between the n-th and the (n+1)-th
separation.

Conventions
-----------
- LSTE: e = δ, the approach of the gear flank towards the pinion flank along the LOA
  under load [m]; positive when the teeth are pressed together, the δ of the mesh force
  law of :mod:`nlgrd` (model.md §2). Without modifications and errors it is the elastic
  deflection W / Σ k_j. Its mean is kept in :class:`LSTEResult`;
  :meth:`LSTEResult.excitation` removes it by default.
- Mesh stiffness: the tangent stiffness k(t) = dW/dδ = Σ_{loaded pairs} 1/c_j [N/m];
  ``k_mean`` is the mean of k(t) over the samples (one period).
- Mesh phase: τ in mesh cycles; one cycle is one base pitch of travel, a pinion
  rotation of 2π/z1. At phase n + τ (n integer) pair slot j is in contact at
  s = s_A + (τ + j) p_b (s from T1, s_A the start of contact) and joins pinion tooth
  (n - j) mod z1 with gear tooth (n - j) mod z2.
- Pairs exist only on the geometric path of contact [s_A, s_E] (no contact outside
  the tip circles, no corner contact).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from nlgrd.errors import ModelError, check_finite, check_positive
from nlgrd.gear.geometry import GearGeometry
from nlgrd.gear.modifications import GearErrors, ProfileModification
from nlgrd.gear.tooth_stiffness import pair_compliance, pitch_point_stiffness


def _separations(
    geometry: GearGeometry,
    modifications: ProfileModification,
    err: dict[str, NDArray],
    positions: NDArray,
    pinion_tooth: NDArray,
    gear_tooth: NDArray,
) -> NDArray:
    s_a, s_e, s_c = geometry.start_of_contact, geometry.end_of_contact, geometry.pitch_point
    g_alpha = s_e - s_a
    sep = modifications.total_relief(geometry, positions)
    sep = sep - err["spacing_pinion"][pinion_tooth] - err["spacing_gear"][gear_tooth]
    sep = sep - err["profile_slope_pinion"][pinion_tooth] * (positions - s_c) / g_alpha
    sep = sep - err["profile_slope_gear"][gear_tooth] * (s_c - positions) / g_alpha
    return sep


def share_load(load: float, separation: NDArray, stiffness: NDArray) -> tuple[NDArray, NDArray]:
    """Solve Σ_j max(0, (δ - σ_j) k_j) = W exactly, sample by sample.

    Parameters
    ----------
    load : float
        Mesh load W along the LOA [N], > 0.
    separation : ndarray, shape (n, J)
        Initial separations σ_j [m]; +inf (or NaN) for slots without a pair.
    stiffness : ndarray, shape (n, J)
        Pair stiffnesses k_j = 1/c_j [N/m]; ignored where the separation is not finite.

    Returns
    -------
    delta : ndarray, shape (n,)
        Approach δ [m].
    loads : ndarray, shape (n, J)
        Pair loads F_j [N] (0 for absent or separated pairs).

    Raises
    ------
    ModelError
        When some sample has no tooth pair in contact.
    """
    sep = np.where(np.isfinite(separation), separation, np.inf)
    k = np.where(np.isfinite(sep), stiffness, 0.0)
    if np.any(~np.isfinite(sep).any(axis=1)):
        raise ModelError("mesh", "no tooth pair in contact at some mesh position")
    order = np.argsort(sep, axis=1)
    s_sorted = np.take_along_axis(sep, order, axis=1)
    k_sorted = np.take_along_axis(k, order, axis=1)
    finite = np.isfinite(s_sorted)
    ks = np.cumsum(np.where(finite, k_sorted, 0.0), axis=1)
    kss = np.cumsum(np.where(finite, k_sorted * np.where(finite, s_sorted, 0.0), 0.0), axis=1)
    with np.errstate(divide="ignore", invalid="ignore"):
        delta_n = (load + kss) / ks
    nxt = np.concatenate([s_sorted[:, 1:], np.full((len(sep), 1), np.inf)], axis=1)
    valid = finite & (delta_n >= s_sorted) & (delta_n <= nxt)
    first = np.argmax(valid, axis=1)
    if not np.all(valid[np.arange(len(sep)), first]):  # pragma: no cover - guarded by monotonicity
        raise RuntimeError("load sharing found no consistent set of loaded pairs")
    delta = delta_n[np.arange(len(sep)), first]
    present = np.isfinite(sep)
    gap = delta[:, None] - np.where(present, sep, 0.0)
    loads = np.where(present, np.maximum(0.0, gap * k), 0.0)
    return delta, loads


@dataclass(frozen=True, eq=False)
class LSTEResult:
    """Loaded static transmission error and load sharing over one period; SI units.

    Parameters
    ----------
    geometry : GearGeometry
        The gear pair.
    mesh_load : float
        Mesh load W along the line of action [N].
    modifications : ProfileModification
        Tip reliefs used.
    errors : GearErrors
        Gear errors used.
    phase : ndarray, shape (n,)
        Mesh phase [mesh cycles], uniform on [0, n_cycles).
    lste : ndarray, shape (n,)
        Loaded static transmission error δ along the LOA [m] (approach, positive when
        the teeth are pressed together; mean kept).
    mesh_stiffness : ndarray, shape (n,)
        Tangent mesh stiffness k(t) = dW/dδ = Σ_{loaded pairs} k_j [N/m].
    pair_loads : ndarray, shape (n, J)
        Load on each pair slot [N]; slot j is the pair that entered j cycles ago.
    pair_positions : ndarray, shape (n, J)
        Contact position s of each slot from T1 [m]; NaN when the slot has no pair.
    separations : ndarray, shape (n, J)
        Initial (unloaded) separation of each slot [m]; NaN when the slot has no pair.
    pair_stiffness : ndarray, shape (n, J)
        Stiffness of each slot's pair k_j [N/m]; NaN when the slot has no pair.
    n_cycles : int
        Mesh cycles in the period (1, or the hunting period with tooth-to-tooth errors).
    """

    geometry: GearGeometry
    mesh_load: float
    modifications: ProfileModification
    errors: GearErrors
    phase: NDArray
    lste: NDArray
    mesh_stiffness: NDArray
    pair_loads: NDArray
    pair_positions: NDArray
    separations: NDArray
    pair_stiffness: NDArray
    n_cycles: int = 1

    # ---------------------------------------------------------------- summaries
    @property
    def points_per_cycle(self) -> int:
        """Samples per mesh cycle."""
        return len(self.phase) // self.n_cycles

    @property
    def k_mean(self) -> float:
        """Average mesh stiffness: the mean of k(t) over the period [N/m]."""
        return float(np.mean(self.mesh_stiffness))

    @property
    def mean(self) -> float:
        """Mean LSTE e0 [m]."""
        return float(np.mean(self.lste))

    @property
    def fluctuation_pp(self) -> float:
        """Peak-to-peak LSTE max δ - min δ over the period [m]."""
        return float(np.ptp(self.lste))

    @property
    def unloaded_ste(self) -> NDArray:
        """Unloaded (no-load) static transmission error: the smallest separation [m]."""
        return np.nanmin(self.separations, axis=1)

    @property
    def pinion_rotation(self) -> NDArray:
        """Pinion rotation angle 2π phase / z1 [rad]."""
        return 2 * np.pi * self.phase / self.geometry.teeth_pinion

    @property
    def pair_roll_angles(self) -> NDArray:
        """Pinion roll angle s / r_b1 of each slot's contact point [rad] (NaN if none)."""
        return self.pair_positions / self.geometry.base_radius_pinion

    @property
    def teeth_in_contact(self) -> NDArray:
        """Number of loaded pairs at each sample [-]."""
        return np.sum(self.pair_loads > 0, axis=1)

    # ---------------------------------------------------------------- Fourier
    def fourier(self, H: int) -> NDArray:
        """Complex Fourier coefficients of the LSTE at the mesh harmonics [m].

        Returns E_m, m = 0 .. H, with E_0 = e0 and E_m = a_m - i b_m, so
        that e(t) ≈ Re Σ_m E_m exp(i m ω t) = e0 + Σ_m a_m cos(m ω t) + b_m sin(m ω t),
        ω the mesh frequency and ω t = 2π phase. Over a hunting period of N cycles the
        coefficients are those of the orders m N of the period (the rotation-order
        sidebands are left out).
        """
        H = int(H)
        if H < 0:
            raise ValueError("H must be >= 0")
        n = len(self.lste)
        if 2 * H * self.n_cycles >= n:
            raise ValueError(
                f"{H} harmonics need more than {2 * H} points per cycle (have {self.points_per_cycle})"
            )
        spec = np.fft.rfft(self.lste) / n
        out = np.empty(H + 1, dtype=complex)
        out[0] = spec[0].real
        out[1:] = 2.0 * spec[self.n_cycles * np.arange(1, H + 1)]
        return out

    def excitation(self, H: int, keep_mean: bool = False):
        """The LSTE as a :class:`~nlgrd.gear.lste_file.MeshExcitation` with ``H`` harmonics.

        ``keep_mean=False`` (default) sets e0 = 0: the static deflection then comes from
        the mean mesh load acting on k_h, not twice.
        """
        from nlgrd.gear.lste_file import MeshExcitation

        E = self.fourier(H)
        return MeshExcitation(
            e0=float(E[0].real) if keep_mean else 0.0,
            a=np.real(E[1:]).copy(),
            b=-np.imag(E[1:]).copy(),
        )

    # ---------------------------------------------------------------- output
    def to_frame(self):
        """Tidy :class:`pandas.DataFrame`, one row per sample, units in the column names
        (docs/conventions.md, "Column names": tooth pair j's columns ``pair<j>.<quantity>``)."""
        import pandas as pd

        from nlgrd.units import column, um

        data = {
            "phase [cycles]": self.phase,
            "pinion_rotation [rad]": self.pinion_rotation,
            "lste [um]": um(self.lste),
            "unloaded_ste [um]": um(self.unloaded_ste),
            "mesh_stiffness [N/m]": self.mesh_stiffness,
            "teeth_in_contact [-]": self.teeth_in_contact,
        }
        for j in range(self.pair_loads.shape[1]):
            data[column("position", "um", f"pair{j}")] = um(self.pair_positions[:, j])
            data[column("load", "N", f"pair{j}")] = self.pair_loads[:, j]
        return pd.DataFrame(data)

    def plot(self, ax=None, kind: Literal["lste", "stiffness", "load_sharing"] = "lste", **kwargs):
        """Plot the LSTE (default), the mesh stiffness or the load sharing; returns the axes."""
        from nlgrd.plotting import gear as gplot

        funcs = {
            "lste": gplot.plot_lste,
            "stiffness": gplot.plot_mesh_stiffness,
            "load_sharing": gplot.plot_load_sharing,
        }
        if kind not in funcs:
            raise ValueError(f"kind must be one of {sorted(funcs)}, got {kind!r}")
        return funcs[kind](self, ax=ax, **kwargs)


def loaded_static_transmission_error(
    geometry: GearGeometry,
    mesh_load: float,
    modifications: ProfileModification | None = None,
    errors: GearErrors | None = None,
    points_per_cycle: int = 256,
    cycles: int | None = None,
) -> LSTEResult:
    """Load sharing and LSTE of a spur pair under a static mesh load.

    Parameters
    ----------
    geometry : GearGeometry
        The gear pair (the pinion drives).
    mesh_load : float
        Mesh load W along the line of action [N], > 0 (W = T_p / r_b1).
    modifications : ProfileModification, optional
        Tip reliefs; none by default.
    errors : GearErrors, optional
        Spacing and profile slope errors; none by default.
    points_per_cycle : int
        Samples per mesh cycle (uniform, endpoint excluded).
    cycles : int, optional
        Mesh cycles to compute; default: the period of the error pattern
        (:meth:`GearErrors.hunting_cycles`), 1 for identical teeth.

    Returns
    -------
    LSTEResult
        LSTE, mesh stiffness and load sharing at every sample.

    Raises
    ------
    ModelError
        On a non-positive load, modifications or errors of the wrong type, fewer than 8
        points per cycle or fewer than 1 cycle.
    """
    check_positive("mesh_load", mesh_load)
    modifications = ProfileModification() if modifications is None else modifications
    errors = GearErrors() if errors is None else errors
    if not isinstance(modifications, ProfileModification):
        raise ModelError(
            "modifications", f"must be a ProfileModification, got {type(modifications).__name__}"
        )
    if not isinstance(errors, GearErrors):
        raise ModelError("errors", f"must be a GearErrors, got {type(errors).__name__}")
    n_pc = int(points_per_cycle)
    if n_pc < 8:
        raise ModelError("points_per_cycle", f"must be at least 8, got {points_per_cycle!r}")
    err = errors.arrays(geometry)
    n_cyc = errors.hunting_cycles(geometry) if cycles is None else int(cycles)
    if n_cyc < 1:
        raise ModelError("cycles", f"must be at least 1, got {cycles!r}")

    s_a, s_e, p_b = geometry.start_of_contact, geometry.end_of_contact, geometry.base_pitch
    n_slots = int(math.floor(geometry.contact_ratio)) + 1
    tau = np.arange(n_pc) / n_pc
    pos = s_a + (tau[:, None] + np.arange(n_slots)[None, :]) * p_b  # (n_pc, J)
    tol = 1e-12 * p_b
    in_contact = pos <= s_e + tol
    pos = np.where(in_contact, np.minimum(pos, s_e), np.nan)

    # pair compliance only where a pair exists, once per cycle (the same every cycle)
    k_cycle = np.full(pos.shape, np.nan)
    k_cycle[in_contact] = pair_compliance(geometry, pos[in_contact]).stiffness

    cycle_index = np.repeat(np.arange(n_cyc), n_pc)
    positions = np.tile(pos, (n_cyc, 1))
    stiffness = np.tile(k_cycle, (n_cyc, 1))
    slots = np.arange(n_slots)[None, :]
    pinion_tooth = np.mod(cycle_index[:, None] - slots, geometry.teeth_pinion)
    gear_tooth = np.mod(cycle_index[:, None] - slots, geometry.teeth_gear)
    sep = _separations(
        geometry, modifications, err, np.nan_to_num(positions, nan=s_a), pinion_tooth, gear_tooth
    )
    sep = np.where(np.isfinite(positions), sep, np.nan)

    delta, loads = share_load(float(mesh_load), sep, stiffness)
    k_t = np.sum(np.where(loads > 0, np.nan_to_num(stiffness), 0.0), axis=1)
    phase = cycle_index + np.tile(tau, n_cyc)
    return LSTEResult(
        geometry=geometry,
        mesh_load=float(mesh_load),
        modifications=modifications,
        errors=errors,
        phase=phase,
        lste=delta,
        mesh_stiffness=k_t,
        pair_loads=loads,
        pair_positions=positions,
        separations=sep,
        pair_stiffness=stiffness,
        n_cycles=n_cyc,
    )


def single_pair_deflection(geometry: GearGeometry, mesh_load: float) -> float:
    """Deflection W / k_t(C) of one tooth pair at the pitch point under the load W [m].

    The classical estimate of the tip relief that smooths the LSTE at that load
    (Harris 1958, Proc. IMechE 172:87; Lin et al. 1994).

    Parameters
    ----------
    geometry : GearGeometry
        The gear pair.
    mesh_load : float
        Mesh load W along the line of action [N], > 0.

    Returns
    -------
    float
        W / k_t(C) [m].

    Raises
    ------
    ModelError
        When ``mesh_load`` is not positive.
    """
    check_positive("mesh_load", mesh_load)
    return float(mesh_load) / pitch_point_stiffness(geometry)


@dataclass(frozen=True, eq=False)
class TipReliefSweep:
    """LSTE summaries over a range of tip-relief amounts (the same on pinion and gear).

    Parameters
    ----------
    amounts : ndarray
        Tip-relief amounts C [m].
    fluctuation_pp : ndarray
        Peak-to-peak LSTE for each amount [m].
    mean_lste : ndarray
        Mean LSTE for each amount [m].
    k_mean : ndarray
        Mean tangent mesh stiffness for each amount [N/m].
    mesh_load : float
        Mesh load along the LOA [N].
    shape : str
        Relief shape, "linear" or "parabolic".
    """

    amounts: NDArray
    fluctuation_pp: NDArray
    mean_lste: NDArray
    k_mean: NDArray
    mesh_load: float
    shape: str

    @property
    def optimum(self) -> float:
        """Relief amount with the smallest peak-to-peak LSTE among those swept [m]."""
        return float(self.amounts[int(np.argmin(self.fluctuation_pp))])

    def to_frame(self):
        """Tidy :class:`pandas.DataFrame` with units in the column names."""
        import pandas as pd

        return pd.DataFrame(
            {
                "tip relief [um]": self.amounts * 1e6,
                "lste peak-to-peak [um]": self.fluctuation_pp * 1e6,
                "lste mean [um]": self.mean_lste * 1e6,
                "mean mesh stiffness [N/m]": self.k_mean,
            }
        )

    def plot(self, ax=None, design_deflection: float | None = None):
        """See :func:`nlgrd.plotting.gear.plot_tip_relief_sweep`."""
        from nlgrd.plotting.gear import plot_tip_relief_sweep

        return plot_tip_relief_sweep(self, ax=ax, design_deflection=design_deflection)


def tip_relief_sweep(
    geometry: GearGeometry,
    mesh_load: float,
    amounts: ArrayLike,
    shape: Literal["linear", "parabolic"] = "linear",
    start_roll_angle_pinion: float | None = None,
    start_roll_angle_gear: float | None = None,
    points_per_cycle: int = 256,
) -> TipReliefSweep:
    """LSTE fluctuation against the tip-relief amount, equal on pinion and gear.

    Parameters
    ----------
    geometry : GearGeometry
        The gear pair.
    mesh_load : float
        Mesh load along the LOA [N].
    amounts : array_like
        Relief amounts to try [m], >= 0.
    shape : {"linear", "parabolic"}
        Relief shape.
    start_roll_angle_pinion, start_roll_angle_gear : float, optional
        Start of relief [rad]; default the highest point of single tooth contact.
    points_per_cycle : int
        Samples per mesh cycle.

    Returns
    -------
    TipReliefSweep
        Peak-to-peak and mean LSTE [m] and mean mesh stiffness [N/m] per amount.
    """
    amounts = np.atleast_1d(np.asarray(amounts, dtype=float))
    check_finite("amounts", amounts)
    pp, mean, km = [], [], []
    for c in amounts:
        mod = ProfileModification(
            tip_relief_pinion=float(c),
            tip_relief_gear=float(c),
            start_roll_angle_pinion=start_roll_angle_pinion,
            start_roll_angle_gear=start_roll_angle_gear,
            shape=shape,
        )
        r = loaded_static_transmission_error(geometry, mesh_load, mod, points_per_cycle=points_per_cycle)
        pp.append(r.fluctuation_pp)
        mean.append(r.mean)
        km.append(r.k_mean)
    return TipReliefSweep(
        amounts=amounts,
        fluctuation_pp=np.array(pp),
        mean_lste=np.array(mean),
        k_mean=np.array(km),
        mesh_load=float(mesh_load),
        shape=shape,
    )

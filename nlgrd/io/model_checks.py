"""Plausibility checks of a whole model, after its parts have been built.

The model classes check their own fields (a negative diameter, a node out of range).
What only the whole model shows, or what is legal but physically absurd, is checked
here, by :func:`check_model` (run by :func:`nlgrd.io.model_file.model_from_dict`) and
:func:`check_gear_files` (run by :func:`nlgrd.io.model_file.load_model`, which knows where
the files are). Each check raises one :class:`~nlgrd.errors.ModelError` naming the key
path, e.g. ``gear_pairs[0].torque``.

Checks
------
- Shaft names are unique (a shaft may be referred to by name).
- No zero bearing stiffness leaves the rig unsupported, decided from the structure,
  not from eigenvalues: shafts joined by couplings with lateral or tilt stiffness form
  a group; a group is held in y (z) by its supports, bearings with kyy (kzz) > 0 and
  couplings to the ground with lateral stiffness. It floats when it has none; a group
  of one shaft without a tilt coupling to the ground pivots when they all sit at one
  node (a bearing carries no moment). Floating or pivoting is an error when a bearing
  of the group has zero stiffness in that direction, or when the group carries a
  loaded gear (its mesh force could not be balanced; a force through the pivot node
  is). Gear meshes do not count as supports: they act along the line of action only
  and lose contact in the backlash. A model without bearings (a free-free rotor) is
  legal.
- A material's density, Young's modulus and Poisson ratio lie in the ranges of solids
  (:data:`MATERIAL_RANGES`); the shear modulus E / 2(1 + nu) then does too.
- A damping ratio is at most 1 (critical damping); a loss factor at most 2 (η = 2ζ).
- No two gear pairs mesh the same two gears (the mesh given twice).
- The static mesh deflection W_0 / k_h is less than the tooth depth.
- An unbalance sits on a shaft that turns (speed ratio not 0).
- An LSTE file is readable and its peak-to-peak value is below the tooth depth and
  below 100 times the backlash.
- A mesh-stiffness file is readable and usable (:mod:`nlgrd.gear.stiffness_file`), and
  the mean of a file in N/m is within a factor 10 of the k_h the dynamics use.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from nlgrd.errors import ModelError
from nlgrd.rotor.system import RotorSystem

__all__ = [
    "MAX_PITCH_LINE_VELOCITY",
    "check_gear_files",
    "check_lste_files",
    "check_model",
    "check_pitch_line_velocity",
    "check_stiffness_files",
    "tooth_depth",
]

#: An LSTE fluctuation this many times the total backlash is refused. Real LSTEs are a
#: few um against backlashes of tens to hundreds of um; a factor 100 (two orders of
#: magnitude) leaves room for near-zero-backlash studies and still catches a file in
#: um read as metres (a factor 1e6).
LSTE_BACKLASH_FACTOR = 100.0


#: Ranges of the solids a shaft or gear can be made of (Ashby 2011, Materials Selection
#: in Mechanical Design, 4th ed., ch. 4 property charts): density up to osmium's
#: 22.6e3 kg/m^3 (no lower bound beyond > 0: a near-massless shaft, as in Kubo's rig,
#: is a modelling choice); Young's modulus from soft polymers (0.1 GPa) to diamond
#: (1.2 TPa); Poisson's ratio of isotropic engineering solids 0 to 0.5. A modulus in
#: GPa or MPa, or a density in g/m^3, falls outside.
MATERIAL_RANGES = {
    "density": (0.0, 25e3, "kg/m^3"),
    "young_modulus": (1e8, 1.2e12, "Pa"),
    "poisson_ratio": (0.0, 0.5, "-"),
}


def _check_materials(system: RotorSystem) -> None:
    owners = [(f"materials.{name}", m) for name, m in _materials(system).items()]
    owners += [
        (f"gear_pairs[{i}].geometry", g.geometry) for i, g in enumerate(system.gear_pairs) if _is_gear_mesh(g)
    ]
    for where, m in owners:
        for field, (low, high, unit) in MATERIAL_RANGES.items():
            value, u = getattr(m, field, None), "" if unit == "-" else f" {unit}"
            if value is not None and not low <= value <= high:
                raise ModelError(
                    f"{where}.{field}",
                    f"{value!r}{u} is outside the range of solids, {low:g} to {high:g}{u}",
                )


#: Largest pitch-line velocity [m/s] of a sweep. A thin steel rim turning at v carries
#: the hoop stress rho v^2 (Timoshenko 1956, Strength of Materials II, sec. 30): 700 MPa
#: at 300 m/s with rho = 7850 kg/m^3, at the strength of gear steels; the model neglects
#: the centrifugal loads that govern well before.
MAX_PITCH_LINE_VELOCITY = 300.0


def check_pitch_line_velocity(gear_pair, omega: float, key: str, given: str) -> None:
    """Refuse a mesh frequency that moves the pinion's pitch circle faster than
    :data:`MAX_PITCH_LINE_VELOCITY`: v = omega r_w1 / z1.

    Parameters
    ----------
    gear_pair : nlgrd.gear.mesh.GearMesh
        The gear pair whose mesh frequency ``omega`` is.
    omega : float
        The highest mesh frequency of the range [rad/s].
    key : str
        The option or key of the range, named in the error (``--rpm``, ``analysis.rpm``).
    given : str
        The range as the user gave it, quoted in the error.

    Raises
    ------
    ModelError
        When the pitch-line velocity exceeds the limit.
    """
    g = gear_pair.geometry
    v = omega * g.operating_pitch_radius_pinion / g.teeth_pinion
    if v > MAX_PITCH_LINE_VELOCITY:
        raise ModelError(
            key,
            f"{given} reaches a pitch-line velocity of {v:.3g} m/s, above the model's limit of "
            f"{MAX_PITCH_LINE_VELOCITY:g} m/s (a steel rim's hoop stress rho v^2 is 700 MPa there)",
        )


def check_speed_range(system: RotorSystem, top: float, in_rpm: bool, key: str, given: str) -> None:
    """Refuse a speed range whose top moves any gear pair's pitch circle faster than
    :data:`MAX_PITCH_LINE_VELOCITY`, with the speeds read as every analysis reads them: rpm
    of the reference shaft, or Hz of the base frequency of the model's frequency plan
    (:meth:`~nlgrd.nonlinear.links.frequency_plan.FrequencyPlan.of_model`: the mesh
    frequency of one mesh, the mesh frequency / N when its errors repeat every N mesh
    cycles, the common period of several meshes).

    Parameters
    ----------
    system : RotorSystem
        The model.
    top : float
        The range's highest speed [rpm or Hz].
    in_rpm : bool
        Whether ``top`` is a shaft speed [rpm] rather than a base frequency [Hz].
    key : str
        The option or key of the range, named in the error.
    given : str
        The range as the user gave it, quoted in the error.

    Raises
    ------
    ModelError
        When a gear pair's pitch-line velocity exceeds the limit.
    """
    from nlgrd.nonlinear.links.frequency_plan import FrequencyPlan

    pairs = [g for g in system.gear_pairs if hasattr(g, "geometry")]
    if not pairs:
        return
    # the reference shaft's speed [rad/s]; Hz are of the plan's base (mesh, mesh/N, common)
    speed = top * math.pi / 30
    if not in_rpm:
        speed = 2 * math.pi * top * FrequencyPlan.of_model(system).speed_per_base
    for gp in pairs:
        mesh = speed * gp.geometry.teeth_pinion * abs(system.shafts[gp.pinion_shaft].speed_ratio)
        check_pitch_line_velocity(gp, mesh, key, given)


def check_harmonics_memory(system: RotorSystem, H: int | None, key: str) -> None:
    """Refuse H harmonics that the model's harmonic balance cannot hold in memory
    (:func:`nlgrd.nonlinear.tracing.harmonic_ladder.max_harmonics` of its DOFs and link
    coordinates): the one bound of ``--harmonics`` and a study's ``analysis.harmonics``.

    Parameters
    ----------
    system : RotorSystem
        The model.
    H : int or None
        The harmonics asked for (None: chosen by the error estimate, nothing to check).
    key : str
        The option or key, named in the error.

    Raises
    ------
    ModelError
        When H exceeds the bound.
    """
    if H is None:
        return
    from nlgrd.nonlinear.tracing.harmonic_ladder import available_memory, max_harmonics

    n_coords = max(1, len(system.gear_pairs) + 2 * len(getattr(system, "bearing_clearances", ())))
    top = max_harmonics(system.dofs.n_dofs, n_coords)
    if H > top:
        raise ModelError(
            key,
            f"{H} harmonics of a model with {system.dofs.n_dofs} DOFs and {n_coords} link coordinates "
            f"need more memory than available ({available_memory() / 2**30:.1f} GiB); at most {top}",
        )


def _check_duplicate_meshes(system: RotorSystem) -> None:
    seen: dict[frozenset, int] = {}
    for i, g in enumerate(system.gear_pairs):
        nodes = frozenset({(g.pinion_shaft, g.pinion_node), (g.gear_shaft, g.gear_node)})
        if nodes in seen:
            j = seen[nodes]
            raise ModelError(
                f"gear_pairs[{i}]",
                f"meshes the same two gears as gear_pairs[{j}] (shaft {g.pinion_shaft} node "
                f"{g.pinion_node} with shaft {g.gear_shaft} node {g.gear_node}): give each mesh once",
            )
        seen[nodes] = i


def check_model(system: RotorSystem) -> None:
    """Raise :class:`ModelError` for a model that is legal field by field but absurd as a whole.

    Runs the checks listed in the module docstring except the LSTE files (:func:`check_lste_files`).

    Parameters
    ----------
    system : RotorSystem
        The model, built.

    Raises
    ------
    ModelError
        For the first check that fails (repeated shaft names, an unsupported group of shafts,
        a damping ratio above 1 or loss factor above 2, an unbalance on a shaft that does not
        turn, a static mesh deflection above the tooth depth), naming the key path.
    """
    _check_shaft_names(system)
    _check_materials(system)
    _check_support(system)
    _check_damping(system)
    for i, u in enumerate(system.unbalance):
        if system.shafts[u.shaft].speed_ratio == 0:
            raise ModelError(
                f"unbalance[{i}].shaft",
                f"shaft {u.shaft} does not turn (speed_ratio = 0): no unbalance force",
            )
    _check_duplicate_meshes(system)
    for i, g in enumerate(system.gear_pairs):
        if _is_gear_mesh(g):
            _check_static_deflection(g, f"gear_pairs[{i}]")


def check_lste_files(system: RotorSystem) -> None:
    """Raise :class:`ModelError` for an unreadable or implausible ``lste_file`` of a gear pair.

    Relative paths are taken from the current directory: :func:`nlgrd.io.model_file.load_model`
    makes them relative to the model file first.

    Parameters
    ----------
    system : RotorSystem
        The model, built; only its gear meshes with an ``lste_file`` are checked.

    Raises
    ------
    ModelError
        When a file cannot be read or used, or its peak-to-peak LSTE [m] exceeds the tooth
        depth or :data:`LSTE_BACKLASH_FACTOR` times the backlash (``gear_pairs[i].lste_file``).
    """
    from nlgrd.gear.lste_file import read_excitation

    for i, g in enumerate(system.gear_pairs):
        path = getattr(g, "lste_file", None)
        if not path or not _is_gear_mesh(g):
            continue
        key = f"gear_pairs[{i}].lste_file"
        z1 = g.geometry.teeth_pinion
        ex = _read_gear_file(key, path, lambda path=path, z1=z1: read_excitation(path, teeth_pinion=z1))
        pp = ex.peak_to_peak
        depth = tooth_depth(g.geometry)
        backlash = g.geometry.backlash
        if pp > depth:
            raise ModelError(
                key,
                f"the LSTE in {path} fluctuates by {pp:.4g} m peak to peak, more than the tooth depth "
                f"{depth:.4g} m (and the backlash {backlash:.4g} m): check the unit (ste_m or ste_um)",
            )
        if backlash > 0 and pp > LSTE_BACKLASH_FACTOR * backlash:
            raise ModelError(
                key,
                f"the LSTE in {path} fluctuates by {pp * 1e6:.4g} um peak to peak, {pp / backlash:.0f} "
                f"times the backlash ({backlash * 1e6:.4g} um; at most {LSTE_BACKLASH_FACTOR:g} times "
                "is accepted): check the unit (ste_m or ste_um)",
            )


def _read_gear_file(key: str, path, read):
    """``read()``, its failures as one :class:`ModelError` naming ``key`` and ``path``."""
    try:
        return read()
    except ModelError as exc:
        detail = f"{exc.key}: {exc.message}" if exc.key else exc.message
        raise ModelError(key, f"cannot use {path}: {detail}") from None
    except OSError as exc:
        raise ModelError(key, f"cannot read {path}: {exc.strerror or exc}") from None
    except (ValueError, LookupError, TypeError) as exc:
        raise ModelError(key, f"cannot read {path}: {type(exc).__name__}: {exc}") from None


def check_gear_files(system: RotorSystem) -> None:
    """Raise :class:`ModelError` for an unusable ``lste_file`` or ``stiffness_file`` of a gear pair.

    Parameters
    ----------
    system : RotorSystem
        The model, built, with the files' paths as they are to be opened.

    Raises
    ------
    ModelError
        From :func:`check_lste_files` or :func:`check_stiffness_files`.
    """
    check_lste_files(system)
    check_stiffness_files(system)


def check_stiffness_files(system: RotorSystem) -> None:
    """Raise :class:`ModelError` for an unreadable or implausible ``stiffness_file`` of a gear pair.

    Relative paths are taken from the current directory, as by :func:`check_lste_files`.

    Parameters
    ----------
    system : RotorSystem
        The model, built; only its gear meshes with a ``stiffness_file`` are checked.

    Raises
    ------
    ModelError
        ``gear_pairs[i].stiffness_file``: when a file cannot be read or used (its message
        names the file and the column), or the mean of a file in N/m is more than
        :data:`~nlgrd.gear.stiffness_file.MEAN_FACTOR` times above or below the mesh's k_h.
    """
    from nlgrd.gear.stiffness_file import MEAN_FACTOR

    for i, g in enumerate(system.gear_pairs):
        path = getattr(g, "stiffness_file", None)
        if not path or not _is_gear_mesh(g):
            continue
        key = f"gear_pairs[{i}].stiffness_file"
        shape = _read_gear_file(key, path, g.stiffness_shape)
        if shape.mean is None:
            continue
        try:
            k_h = g.stiffness()
        except ModelError:
            continue  # refused elsewhere with its own message
        if not 1 / MEAN_FACTOR <= shape.mean / k_h <= MEAN_FACTOR:
            source = "mesh_stiffness" if g.mesh_stiffness is not None else "computed from the geometry"
            raise ModelError(
                key,
                f"the stiffness in {path} has the mean {shape.mean:.4g} N/m, {shape.mean / k_h:.3g} times "
                f"the k_h = {k_h:.4g} N/m of the dynamics ({source}; at most a factor {MEAN_FACTOR:g} is "
                "accepted): check the unit (N/m); only the file's shape k / mean(k) is used, with k_h",
            )


def tooth_depth(geometry) -> float:
    """Whole depth of the teeth, (h_a* + h_f*) m [m]: 2.25 m for standard teeth.

    Parameters
    ----------
    geometry : GearGeometry
        The gear pair's geometry: its ``module`` [m] and addendum and dedendum
        coefficients [-].

    Returns
    -------
    float
        The tooth depth [m].
    """
    return (geometry.addendum_coefficient + geometry.dedendum_coefficient) * geometry.module


# ------------------------------------------------------------------------------------


def _is_gear_mesh(g) -> bool:
    from nlgrd.gear.mesh import GearMesh

    return isinstance(g, GearMesh)


def _check_shaft_names(system: RotorSystem) -> None:
    seen: dict[str, int] = {}
    for i, s in enumerate(system.shafts):
        if not s.name:
            continue
        if s.name in seen:
            raise ModelError(
                f"shafts[{i}].name",
                f"{s.name!r} is also the name of shafts[{seen[s.name]}]; shaft names must be unique",
            )
        seen[s.name] = i


def _check_damping(system: RotorSystem) -> None:
    for i, g in enumerate(system.gear_pairs):
        zeta = getattr(g, "damping_ratio", None)
        # 1 is critical damping; a mesh has 0.01 to 0.1
        if isinstance(zeta, (int, float)) and zeta > 1:
            raise ModelError(
                f"gear_pairs[{i}].damping_ratio",
                f"{zeta!r} is above 1 (critical damping); gear meshes have about 0.01 to 0.1",
            )
    for name, mat in _materials(system).items():
        # at resonance a loss factor eta acts as a damping ratio eta / 2: above 2 is beyond critical
        if mat.loss_factor > 2:
            raise ModelError(
                f"materials.{name}.loss_factor",
                f"{mat.loss_factor!r} is above 2 (a damping ratio eta / 2 above 1); steels have about 1e-4",
            )


def _materials(system: RotorSystem) -> dict:
    out = {}
    for s in system.shafts:
        for e in s.elements:
            out.setdefault(e.material.name, e.material)
    return out


def _check_static_deflection(g, where: str) -> None:
    """W_0 / k_h must stay below the tooth depth: the teeth cannot deflect by more than their height."""
    load = g.static_load
    if not load > 0:
        return
    try:
        k_h = g.stiffness()
    except (ModelError, ValueError, ArithmeticError, np.linalg.LinAlgError):
        return  # the stiffness itself is refused later, with its own message
    if not (math.isfinite(k_h) and k_h > 0):
        return
    deflection = load / k_h
    depth = tooth_depth(g.geometry)
    if deflection > depth:
        source = "mesh_stiffness" if g.mesh_stiffness is not None else "computed from the geometry"
        raise ModelError(
            f"{where}.torque",
            f"{g.torque:.6g} N m gives a mesh load W_0 = {load:.4g} N and a static mesh deflection "
            f"W_0 / k_h = {deflection:.4g} m (k_h = {k_h:.4g} N/m, {source}), more than the tooth depth "
            f"{depth:.4g} m: check the unit (N m, on the pinion)",
        )


# ------------------------------------------------------------------------------------ support


@dataclasses.dataclass
class _Support:
    """Lateral supports of one direction in a group of shafts."""

    nodes: set = dataclasses.field(default_factory=set)  # (shaft, node) with stiffness to ground
    zero: list = dataclasses.field(default_factory=list)  # bearing indices with zero stiffness here


def _positive(value) -> bool:
    """A direct coefficient counts as support when it is positive at some tabulated speed."""
    return bool(np.max(np.asarray(value, dtype=float)) > 0)


def _groups(system: RotorSystem) -> list[list[int]]:
    """Shafts joined by couplings with lateral or tilt stiffness (union-find)."""
    parent = list(range(len(system.shafts)))

    def find(i: int) -> int:
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i

    for c in system.couplings:
        if not c.grounded and (c.k_lateral > 0 or c.k_tilt > 0):
            parent[find(c.shaft_a)] = find(c.shaft_b)
    out: dict[int, list[int]] = {}
    for i in range(len(system.shafts)):
        out.setdefault(find(i), []).append(i)
    return list(out.values())


def _loaded_mesh_nodes(system: RotorSystem) -> list[tuple[int, int, str]]:
    """(shaft, node, words) of the pinions and gears of gear pairs that carry a static load."""
    out = []
    for i, g in enumerate(system.gear_pairs):
        torque = getattr(g, "torque", 0)
        if isinstance(torque, (int, float)) and torque > 0:
            out.append((g.pinion_shaft, g.pinion_node, f"the pinion of gear_pairs[{i}]"))
            out.append((g.gear_shaft, g.gear_node, f"the gear of gear_pairs[{i}]"))
    return out


def _check_support(system: RotorSystem) -> None:
    """A shaft group left free laterally is an error when a zero-stiffness bearing or a mesh load is involved.

    A model without bearings is a free-free rotor and a shaft on one bearing may be
    meant to pivot: both are legal. The same shape is an error when a declared bearing
    has no stiffness in that direction (a zero typed by mistake), or when the free
    shaft carries a loaded gear, whose static mesh force then cannot be balanced.
    """
    meshes = _loaded_mesh_nodes(system)
    for group in _groups(system):
        members = set(group)
        tilt = any(c.grounded and c.k_tilt > 0 and c.shaft_a in members for c in system.couplings)
        sup = {d: _Support() for d in "yz"}
        for c in system.couplings:
            if c.grounded and c.k_lateral > 0 and c.shaft_a in members:
                for d in "yz":
                    sup[d].nodes.add((c.shaft_a, c.node_a))
        for j, b in enumerate(system.bearings):
            if b.shaft not in members:
                continue
            for d in "yz":
                if _positive(getattr(b, f"k{d}{d}")):
                    sup[d].nodes.add((b.shaft, b.node))
                else:
                    sup[d].zero.append(j)
        for c in system.bearing_clearances:  # contact beyond the clearance holds the journal
            if c.shaft in members and getattr(c, "other_node", None) is None:
                for d in "yz":
                    sup[d].nodes.add((c.shaft, c.node))
        where = _describe(system, group)
        loaded = [m for m in meshes if m[0] in members]
        floating = [d for d in "yz" if not sup[d].nodes]
        if floating:
            if sup[floating[0]].zero:
                raise _unsupported(system, sup, floating, where)
            if loaded:
                raise _mesh_unsupported(loaded[0], floating, where, "floats")
            continue
        if len(group) > 1 or tilt:
            continue
        pivots = {d: {n for _, n in sup[d].nodes} for d in "yz"}
        dirs = [d for d in "yz" if len(pivots[d]) < 2]
        zero = [d for d in dirs if sup[d].zero]
        if zero:
            raise _pivoting(system, sup[zero[0]], zero[0], dirs, where)
        # a mesh force through the pivot node is balanced
        off = [(m, d) for d in dirs for m in loaded if m[1] not in pivots[d]]
        if off:
            m, d = off[0]
            raise _mesh_unsupported(m, [d], where, f"pivots about node {min(pivots[d])}")


def _mesh_unsupported(mesh: tuple[int, int, str], dirs: list[str], where: str, how: str) -> ModelError:
    shaft, node, words = mesh
    return ModelError(
        f"shafts[{shaft}]",
        f"{where} carries {words} (node {node}) but {how} in {' and '.join(dirs)}: no bearing or coupling "
        "to the ground holds it, so the static mesh load cannot be balanced; add [[bearings]] entries",
    )


def _describe(system: RotorSystem, group: list[int]) -> str:
    def label(i: int) -> str:
        name = system.shafts[i].name
        return f"{i} ({name!r})" if name else f"{i}"

    if len(group) == 1:
        return f"shaft {label(group[0])}"
    return f"shafts {', '.join(label(i) for i in group)} (joined by couplings)"


def _zero_key(system: RotorSystem, j: int, d: str) -> tuple[str, str]:
    """Key and words for bearing j without stiffness in direction d (both: the bearing itself)."""
    b = system.bearings[j]
    if not _positive(b.kyy) and not _positive(b.kzz):
        return f"bearings[{j}]", "kyy and kzz are zero"
    return f"bearings[{j}].k{d}{d}", f"k{d}{d} is zero"


def _unsupported(system, sup, floating, where) -> ModelError:
    dirs = " and ".join(floating)
    zero = sup[floating[0]].zero
    key, words = _zero_key(system, zero[0], floating[0])
    others = f" (so are those of {', '.join(f'bearings[{k}]' for k in zero[1:])})" if len(zero) > 1 else ""
    return ModelError(
        key,
        f"{words}{others}, and nothing else supports {where} in {dirs}: the rig floats "
        "laterally; give the bearings radial stiffness",
    )


def _pivoting(system, sup: _Support, d: str, dirs: list[str], where: str) -> ModelError:
    node = min(n for _, n in sup.nodes)
    key, words = _zero_key(system, sup.zero[0], d)
    return ModelError(
        key,
        f"{words}, which leaves {where} held in {' and '.join(dirs)} at node {node} only: the shaft "
        "pivots about it (a bearing carries no moment); give the bearing radial stiffness",
    )

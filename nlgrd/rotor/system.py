"""The rotor system: shafts, disks, bearings, couplings and gear pairs, with its DOF map."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from functools import cached_property
from typing import Any

import numpy as np
from numpy.typing import NDArray

from nlgrd.errors import ModelError
from nlgrd.rotor.bearing import Bearing
from nlgrd.rotor.coupling import Coupling
from nlgrd.rotor.disk import Disk
from nlgrd.rotor.loads import Unbalance
from nlgrd.rotor.shaft import Shaft
from nlgrd.rotor.structural_damping import StructuralDamping

#: Names of the six DOFs of every node, in order. ASCII aliases: tx, ty, tz.
DOF_NAMES = ("ux", "uy", "uz", "θx", "θy", "θz")
_ALIASES = {"tx": "θx", "ty": "θy", "tz": "θz", "thx": "θx", "thy": "θy", "thz": "θz"}
DOFS_PER_NODE = 6


@dataclass(frozen=True)
class DofMap:
    """Global DOF numbering: shaft by shaft, node by node, six DOFs per node.

    Global index of (shaft s, node n, dof d) is ``6 * (first_node[s] + n) + d`` with d
    in the order ``(ux, uy, uz, θx, θy, θz)``.

    Parameters
    ----------
    shafts : tuple of Shaft
        The shafts of the system, in order; shafts and nodes count from 0.
    """

    shafts: tuple[Shaft, ...]

    @cached_property
    def first_node(self) -> NDArray:
        """Global number of each shaft's node 0."""
        return np.concatenate([[0], np.cumsum([s.n_nodes for s in self.shafts])[:-1]]).astype(int)

    @property
    def n_nodes(self) -> int:
        """Total number of nodes."""
        return int(sum(s.n_nodes for s in self.shafts))

    @property
    def n_dofs(self) -> int:
        """Total number of DOFs."""
        return DOFS_PER_NODE * self.n_nodes

    def shaft_index(self, shaft: int | str) -> int:
        """Index of a shaft given by index or name."""
        if isinstance(shaft, str):
            names = [s.name for s in self.shafts]
            if shaft not in names:
                raise ModelError("shaft", f"no shaft named {shaft!r}; shafts are {names}")
            return names.index(shaft)
        if not 0 <= shaft < len(self.shafts):
            raise ModelError("shaft", f"shaft index {shaft} out of range 0..{len(self.shafts) - 1}")
        return int(shaft)

    def node_dofs(self, shaft: int | str, node: int) -> NDArray:
        """The six global DOF indices of a node."""
        s = self.shaft_index(shaft)
        if not 0 <= node < self.shafts[s].n_nodes:
            raise ModelError("node", f"node {node} out of range 0..{self.shafts[s].n_nodes - 1} of shaft {s}")
        start = DOFS_PER_NODE * (self.first_node[s] + node)
        return np.arange(start, start + DOFS_PER_NODE)

    def index(self, shaft: int | str, node: int, dof: str) -> int:
        """Global index of one DOF, e.g. ``index(0, 3, "θx")`` or ``index("pinion", 3, "tx")``."""
        d = _ALIASES.get(dof, dof)
        if d not in DOF_NAMES:
            raise ModelError("dof", f"unknown DOF {dof!r}; use one of {DOF_NAMES}")
        return int(self.node_dofs(shaft, node)[DOF_NAMES.index(d)])

    def name(self, index: int) -> str:
        """Readable name of a global DOF, e.g. ``"shaft 0 (pinion), node 3, θx"``."""
        node, d = divmod(int(index), DOFS_PER_NODE)
        s = int(np.searchsorted(self.first_node, node, side="right") - 1)
        label = f" ({self.shafts[s].name})" if self.shafts[s].name else ""
        return f"shaft {s}{label}, node {node - self.first_node[s]}, {DOF_NAMES[d]}"

    def table(self) -> list[tuple[int, int, int, str, float]]:
        """Rows (global index, shaft, node, dof name, axial position [m]) for every DOF."""
        rows = []
        for s, shaft in enumerate(self.shafts):
            for n, x in enumerate(shaft.node_positions):
                for dn in DOF_NAMES:
                    rows.append((self.index(s, n, dn), s, n, dn, float(x)))
        return rows

    def kind_mask(self, kind: str) -> NDArray:
        """Boolean mask of DOFs of one kind: 'axial', 'lateral' or 'torsional'."""
        local = {"axial": [0], "lateral": [1, 2, 4, 5], "torsional": [3]}[kind]
        mask = np.zeros(self.n_dofs, dtype=bool)
        for d in local:
            mask[d::DOFS_PER_NODE] = True
        return mask

    def shaft_mask(self, shaft: int) -> NDArray:
        """Boolean mask of the DOFs of one shaft."""
        mask = np.zeros(self.n_dofs, dtype=bool)
        start = DOFS_PER_NODE * self.first_node[shaft]
        mask[start : start + DOFS_PER_NODE * self.shafts[shaft].n_nodes] = True
        return mask


@dataclass(frozen=True)
class RotorSystem:
    """A set of parallel shafts with disks, bearings, couplings and gear pairs.

    Parameters
    ----------
    shafts : tuple of Shaft
        The shafts; shaft 0 is usually the pinion shaft, whose speed is the reference
        speed Ω of every analysis.
    disks, bearings, couplings : tuples
        Attached parts; each names its shaft and node.
    gear_pairs : tuple
        Gear meshes (:class:`nlgrd.gear.mesh.GearMesh`).
    bearing_clearances : tuple
        Radial clearances of bearings (:class:`nlgrd.nonlinear.links.contract.BearingClearance`),
        nonlinear links: only the link analyses (:mod:`nlgrd.nonlinear.models.link_model`) model
        them.
    name : str
        Label.
    unbalance : tuple of Unbalance
        Mass unbalances (:class:`nlgrd.rotor.loads.Unbalance`), loads of the link analyses
        (:func:`nlgrd.nonlinear.models.link_model.build_link_model`).
    damping : StructuralDamping or None
        Damping of the whole FE rotor (a modal floor, Rayleigh α M + β K): a viscous
        matrix [N s/m] added to the assembled C (:mod:`nlgrd.rotor.structural_damping`);
        None: none.
    """

    shafts: tuple[Shaft, ...]
    disks: tuple[Disk, ...] = ()
    bearings: tuple[Bearing, ...] = ()
    couplings: tuple[Coupling, ...] = ()
    gear_pairs: tuple[Any, ...] = field(default=())
    bearing_clearances: tuple[Any, ...] = field(default=())
    name: str = ""
    unbalance: tuple[Unbalance, ...] = ()
    damping: StructuralDamping | None = None

    def __post_init__(self):
        for key in (
            "shafts",
            "disks",
            "bearings",
            "couplings",
            "gear_pairs",
            "bearing_clearances",
            "unbalance",
        ):
            object.__setattr__(self, key, tuple(getattr(self, key)))
        if not self.shafts:
            raise ModelError("shafts", "a system needs at least one shaft")
        dm = self.dofs
        for group in ("disks", "bearings", "bearing_clearances", "unbalance"):
            for i, part in enumerate(getattr(self, group)):
                self._check_node(dm, f"{group}[{i}]", part.shaft, part.node)
        for i, c in enumerate(self.couplings):
            self._check_node(dm, f"couplings[{i}]", c.shaft_a, c.node_a, "_a")
            if not c.grounded:
                self._check_node(dm, f"couplings[{i}]", c.shaft_b, c.node_b, "_b")
        for i, c in enumerate(self.bearing_clearances):
            if getattr(c, "other_node", None) is not None:
                self._check_node(dm, f"bearing_clearances[{i}]", c.other_shaft, c.other_node, "", "other_")
        for i, g in enumerate(self.gear_pairs):
            self._check_node(dm, f"gear_pairs[{i}]", g.pinion_shaft, g.pinion_node, "", "pinion_")
            self._check_node(dm, f"gear_pairs[{i}]", g.gear_shaft, g.gear_node, "", "gear_")
            for key, shaft in (("input_node", g.pinion_shaft), ("output_node", g.gear_shaft)):
                node = getattr(g, key, None)
                if node is not None:
                    self._check_node(dm, f"gear_pairs[{i}]", shaft, node, "", key.replace("node", ""))
            try:
                if hasattr(g, "check"):
                    g.check(self)
            except ModelError as err:
                raise err.within(f"gear_pairs[{i}]") from None

    @staticmethod
    def _check_node(
        dm: DofMap, where: str, shaft: int, node: int, suffix: str = "", prefix: str = ""
    ) -> None:
        if not 0 <= shaft < len(dm.shafts):
            raise ModelError(
                f"{where}.{prefix}shaft{suffix}", f"shaft {shaft} out of range 0..{len(dm.shafts) - 1}"
            )
        n = dm.shafts[shaft].n_nodes
        if not 0 <= node < n:
            raise ModelError(
                f"{where}.{prefix}node{suffix}", f"node {node} out of range 0..{n - 1} of shaft {shaft}"
            )

    @cached_property
    def dofs(self) -> DofMap:
        """The DOF map."""
        return DofMap(self.shafts)

    @property
    def n_dofs(self) -> int:
        """Number of DOFs."""
        return self.dofs.n_dofs


def refined(system: RotorSystem, factor: int) -> RotorSystem:
    """``system`` with every shaft element split into ``factor`` equal elements.

    Every part stays where it was: node n becomes node ``factor`` n for disks, bearings,
    couplings, gear pairs (and their input and output nodes), bearing clearances
    (and their housings) and unbalances. For mesh-convergence studies and model-size scaling.

    Parameters
    ----------
    system : RotorSystem
        The model.
    factor : int
        Elements per original element [-], >= 1.

    Returns
    -------
    RotorSystem
    """
    f = int(factor)
    if f < 1 or f != factor:
        raise ModelError("factor", f"must be a whole number >= 1, got {factor!r}")
    rep = dataclasses.replace

    def node(n):
        return None if n is None else n * f

    shafts = tuple(
        rep(s, elements=tuple(rep(e, length=e.length / f) for e in s.elements for _ in range(f)))
        for s in system.shafts
    )
    gears = tuple(
        rep(
            g,
            pinion_node=node(g.pinion_node),
            gear_node=node(g.gear_node),
            input_node=node(g.input_node),
            output_node=node(g.output_node),
        )
        for g in system.gear_pairs
    )
    clearances = tuple(
        rep(c, node=node(c.node), other_node=node(c.other_node)) for c in system.bearing_clearances
    )
    return rep(
        system,
        shafts=shafts,
        disks=tuple(rep(d, node=node(d.node)) for d in system.disks),
        bearings=tuple(rep(b, node=node(b.node)) for b in system.bearings),
        couplings=tuple(rep(c, node_a=node(c.node_a), node_b=node(c.node_b)) for c in system.couplings),
        gear_pairs=gears,
        bearing_clearances=clearances,
        unbalance=tuple(rep(u, node=node(u.node)) for u in system.unbalance),
    )

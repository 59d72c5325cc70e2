"""nlgrd: nonlinear dynamics of geared rotor systems.

Finite-element shafts, rigid disks, linear bearings and couplings (linear model);
a spur gear mesh with backlash excited by the loaded static transmission error;
multi-harmonic balance with describing functions reduced by receptances.
Reference: Maliha, Doğruer & Özgüven (2004), J. Mech. Des. 126:534-541.
"""

from nlgrd.analyses import campbell, continuation, load, modes, search_orbits, sweep, time_sweep
from nlgrd.errors import ModelError
from nlgrd.gear.mesh import GearMesh
from nlgrd.nonlinear.links.contract import BearingClearance, GearMeshLink
from nlgrd.rotor.assembly import LinearModel, assemble
from nlgrd.rotor.bearing import Bearing
from nlgrd.rotor.coupling import Coupling
from nlgrd.rotor.disk import Disk
from nlgrd.rotor.loads import Unbalance
from nlgrd.rotor.materials import STEEL, Material
from nlgrd.rotor.shaft import Shaft, ShaftElement
from nlgrd.rotor.system import DofMap, RotorSystem

__version__ = "0.1.0"

__all__ = [
    "Bearing",
    "BearingClearance",
    "Coupling",
    "Disk",
    "DofMap",
    "GearMesh",
    "GearMeshLink",
    "LinearModel",
    "Material",
    "ModelError",
    "RotorSystem",
    "STEEL",
    "Shaft",
    "ShaftElement",
    "Unbalance",
    "assemble",
    "campbell",
    "continuation",
    "load",
    "modes",
    "search_orbits",
    "sweep",
    "time_sweep",
]

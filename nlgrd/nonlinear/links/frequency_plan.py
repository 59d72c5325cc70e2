"""The frequency plan of a harmonic-balance model: how its base frequency relates to the
shaft speed and at which harmonic of the base each excitation sits (issue 11, item 5).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from fractions import Fraction

from nlgrd.errors import ModelError
from nlgrd.rotor.system import RotorSystem


@dataclass(frozen=True)
class FrequencyPlan:
    """How the harmonic-balance base frequency ω relates to the shaft speed.

    Every excitation sits at an integer harmonic of the base: an unbalance on a shaft of
    speed ratio s at |s| Ω, the mesh of a pinion with N_p teeth on a shaft of ratio s_p at
    N_p |s_p| Ω (Ω the reference shaft speed). :meth:`for_system` chooses the longest
    base that makes all of them harmonics: the mesh frequency for one mesh or an idler
    train, their greatest common divisor for a multi-stage train; a shaft order when a
    gear pair's excitation repeats only every N mesh cycles (tooth errors that differ,
    runout: :attr:`~nlgrd.gear.mesh.GearMesh.error_period`).

    Parameters
    ----------
    speed_per_base : float
        Reference shaft speed Ω per unit base frequency, Ω = ``speed_per_base`` ω [-]: 1
        when the base is the shaft speed, 1 / (N_p |s_p|) when it is the mesh frequency.
    name : str
        "shaft", "mesh", "mesh/N" (the mesh frequency / N: errors that repeat every N
        mesh cycles) or "common" (a common divisor of several mesh frequencies).
    """

    speed_per_base: float = 1.0
    name: str = "shaft"

    def speed(self, omega: float) -> float:
        """Reference shaft speed [rad/s] at base frequency ``omega`` [rad/s].

        Parameters
        ----------
        omega : float
            Base frequency [rad/s].

        Returns
        -------
        float
        """
        return float(omega) * self.speed_per_base

    def order(self, shaft_order: float, what: str = "excitation") -> int:
        """The harmonic of the base at which an excitation of ``shaft_order`` Ω sits.

        Parameters
        ----------
        shaft_order : float
            Its frequency per unit reference shaft speed [-].
        what : str
            Named in the error when it is not a harmonic.

        Returns
        -------
        int
        """
        m = abs(float(shaft_order) * self.speed_per_base)
        r = round(m)
        if r < 1 or abs(m - r) > 1e-9 * m:
            raise ModelError(
                "plan",
                f"{what} at {abs(shaft_order):.6g} x the shaft speed is not a harmonic of the "
                f"base frequency ({1 / abs(self.speed_per_base):.6g} x the shaft speed)",
            )
        return int(r)

    def subharmonic(self, nu: int) -> FrequencyPlan:
        """The plan of orbits of ``nu`` base periods: the base ω/ν, every excitation at ν
        times its harmonic here (a mesh at m at ν m), the shaft speed unchanged.

        Parameters
        ----------
        nu : int
            Base periods per period of the new base [-], >= 1.

        Returns
        -------
        FrequencyPlan
            ``speed_per_base`` ν times this one's; the name with "/ν" appended (ν > 1).
        """
        if int(nu) != nu or nu < 1:
            raise ModelError("period", f"a whole number of base periods >= 1, got {nu!r}")
        nu = int(nu)
        return FrequencyPlan(self.speed_per_base * nu, self.name if nu == 1 else f"{self.name}/{nu}")

    @classmethod
    def of_model(cls, system: RotorSystem) -> FrequencyPlan:
        """:meth:`for_system` with the system's own unbalances (each at |s| of its shaft), the
        plan :func:`~nlgrd.nonlinear.models.link_model.build_link_model` uses by default.

        Parameters
        ----------
        system : RotorSystem
            The model.

        Returns
        -------
        FrequencyPlan
        """
        return cls.for_system(system, [abs(system.shafts[u.shaft].speed_ratio) for u in system.unbalance])

    @classmethod
    def for_system(cls, system: RotorSystem, shaft_orders: Sequence[float] = ()) -> FrequencyPlan:
        """The longest base making every mesh and every ``shaft_orders`` a harmonic.

        Parameters
        ----------
        system : RotorSystem
            Its gear pairs' mesh orders N_p |s_p| count, divided by their
            :attr:`~nlgrd.gear.mesh.GearMesh.error_period` (teeth that differ, runout: the
            excitation repeats only after that many mesh cycles).
        shaft_orders : sequence of float
            Further excitations, e.g. |s| of a shaft with unbalance [-].

        Returns
        -------
        FrequencyPlan
            "shaft" without meshes, "mesh" when all excitations sit at one mesh
            frequency, "mesh/N" when their errors repeat every N mesh cycles (each
            mesh's :attr:`~nlgrd.gear.mesh.GearMesh.error_period` N), else "common".
        """
        meshes = [  # a mesh's excitation repeats every error_period mesh cycles
            Fraction(g.geometry.teeth_pinion, g.error_period)
            * Fraction(abs(system.shafts[g.pinion_shaft].speed_ratio)).limit_denominator(10**6)
            for g in system.gear_pairs
        ]
        others = [Fraction(abs(float(o))).limit_denominator(10**6) for o in shaft_orders]
        orders = meshes + others
        if not orders:
            return cls(1.0, "shaft")
        den = math.lcm(*(q.denominator for q in orders))
        base = Fraction(math.gcd(*(int(q * den) for q in orders)), den)
        periods = {g.error_period for g in system.gear_pairs}
        if not others and len(set(meshes)) == 1 and len(periods) == 1:
            n = periods.pop()  # the base is the mesh frequency / the error period
            name = "mesh" if n == 1 else f"mesh/{n}"
        else:
            name = "shaft" if base == 1 else "common"
        return cls(1.0 / float(base), name)

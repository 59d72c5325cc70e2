"""The coexisting branches of a sweep (``nlgrd.sweep(..., coexisting=True)``, ``nlgrd sweep
--coexisting``) as the sweep's result carries them: each branch's points with every link's
outputs, and the bifurcations reported on it, each confirmed on the exact flow or flagged
unconfirmed.

The sweep's table gains a ``branch`` column ("sweep" on its own rows, "coexisting k" on the
rows of the k-th branch, appended; :func:`with_branches`); the bifurcations are a table of
their own (:func:`bifurcation_frame`). docs/conventions.md, "Coexisting branches".
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd

from nlgrd.nonlinear.results.sweep_results import SweepResult

#: The ``branch`` of the sweep's own rows.
SWEEP_BRANCH = "sweep"


@dataclass(frozen=True)
class Bifurcation:
    """A bifurcation reported on a coexisting branch.

    Attributes
    ----------
    direction : str
        "up" or "down": the part of the branch (from the orbit found) it lies on.
    kind : str
        "fold", "period doubling" or "Neimark-Sacker".
    omega : float
        The base frequency [rad/s]: located on the exact flow when ``confirmed``, else the
        middle of the bracket.
    omega_from, omega_to : float
        The rows that bracket it [rad/s] (equal to ``omega`` for a fold located from a
        branch end).
    confirmed : bool
        Located on the exact flow (a shootable model, the branch cut at its first hop);
        False: a change of the harmonic-balance verdict between two rows, not checked.
    """

    direction: str
    kind: str
    omega: float
    omega_from: float
    omega_to: float
    confirmed: bool


@dataclass(frozen=True)
class CoexistingBranch:
    """One coexisting branch: its points, their outputs and its bifurcations.

    Attributes
    ----------
    name : str
        "coexisting k" (k from 1, in the order found).
    result : SweepResult
        The branch (directions "up" and "down" from the orbit found; converged where it
        exists; stable and unstable rows alike).
    links : pandas.DataFrame
        Every link's and linear bearing's outputs per row (SI), at every converged row.
    bifurcations : tuple of Bifurcation
    """

    name: str
    result: SweepResult
    links: pd.DataFrame
    bifurcations: tuple = ()

    def span(self) -> tuple[float, float] | None:
        """The base frequencies of its converged rows, lowest and highest [rad/s] (None:
        no converged row)."""
        w = np.asarray(self.result.omega)[np.asarray(self.result.converged, dtype=bool)]
        return (float(w.min()), float(w.max())) if w.size else None


def with_branches(frame: pd.DataFrame, branches: list[pd.DataFrame], names: list[str]) -> pd.DataFrame:
    """The sweep's table with a ``branch`` column (:data:`SWEEP_BRANCH`) and each branch's
    table appended under its name.

    Parameters
    ----------
    frame : pandas.DataFrame
        The sweep's table.
    branches : list of pandas.DataFrame
        Each branch's table, the same columns.
    names : list of str
        Their names.

    Returns
    -------
    pandas.DataFrame
    """
    parts = [frame.assign(branch=SWEEP_BRANCH)]
    parts += [f.assign(branch=name) for f, name in zip(branches, names, strict=True)]
    out = pd.concat(parts, ignore_index=True) if len(parts) > 1 else parts[0]
    cols = list(out.columns)
    cols.insert(cols.index("direction"), cols.pop(cols.index("branch")))
    return out[cols]


def bifurcation_frame(branches, speed_per_base: float | None = None) -> pd.DataFrame:
    """The bifurcations of the coexisting branches, one row each: ``branch``, ``direction``,
    ``kind``, ``base_frequency [Hz]`` (and ``shaft_speed [rpm]`` when the speed per base
    is known), the bracket ``from [Hz]``, ``to [Hz]``, and ``confirmed``.

    Parameters
    ----------
    branches : sequence of CoexistingBranch
    speed_per_base : float, optional
        Reference shaft speed per base frequency [-].

    Returns
    -------
    pandas.DataFrame
    """
    rows = []
    for b in branches:
        for f in b.bifurcations:
            row = {
                "branch": b.name,
                "direction": f.direction,
                "kind": f.kind,
                "base_frequency [Hz]": f.omega / (2 * np.pi),
            }
            if speed_per_base is not None:
                row["shaft_speed [rpm]"] = f.omega * speed_per_base * 30 / np.pi
            row["from [Hz]"] = f.omega_from / (2 * np.pi)
            row["to [Hz]"] = f.omega_to / (2 * np.pi)
            row["confirmed"] = bool(f.confirmed)
            rows.append(row)
    columns = ["branch", "direction", "kind", "base_frequency [Hz]"]
    columns += ["shaft_speed [rpm]"] if speed_per_base is not None else []
    return pd.DataFrame(rows, columns=[*columns, "from [Hz]", "to [Hz]", "confirmed"])

"""A sweep's coexisting branches as the default flows offer them (``nlgrd.sweep(...,
coexisting=True)``, ``nlgrd sweep --coexisting``): the branches found beside the sweep's
jumps (:func:`~nlgrd.nonlinear.tracing.coexisting.coexisting_branches`), every link's
outputs on them, and their bifurcations, each confirmed or flagged unconfirmed.

On a :func:`~nlgrd.nonlinear.stability.shooting.shootable` model (constant-stiffness
backlash and contact-stop laws with a static force: the exact flow is known) each branch is
cut at its first hop on the exact flow and its bifurcations are located on the exact flow
(:func:`~nlgrd.nonlinear.stability.verdicts.locate_bifurcations`): confirmed. A change of
verdict between two settled rows that the exact flow does not locate is listed too,
unconfirmed. On any other model (a gear mesh's varying stiffness: every FE model with a
mesh) the exact flow is not known: each branch is cut instead at its first jump in the
outputs (harmonic balance alone; a smooth hop onto another orbit is not seen) and its
changes of verdict between rows are listed, unconfirmed (:data:`NO_EXACT_FLOW`, the one
line the result carries).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pandas as pd

from nlgrd.nonlinear.hb.harmonic_balance import ReducedModel
from nlgrd.nonlinear.results.coexisting_results import Bifurcation, CoexistingBranch
from nlgrd.nonlinear.results.link_results import LinkSweepResult, _jumps_on, bearing_columns, link_rows
from nlgrd.nonlinear.results.metrics import METRIC_UNITS
from nlgrd.nonlinear.results.sweep_results import SweepResult, without_rows
from nlgrd.nonlinear.stability.shooting import shootable
from nlgrd.nonlinear.stability.verdicts import locate_bifurcations
from nlgrd.nonlinear.tracing.coexisting import coexisting_branches
from nlgrd.nonlinear.tracing.harmonic_convergence import next_harmonics

#: What is done on a model whose exact flow is not known (:func:`with_coexisting`).
NO_EXACT_FLOW = (
    "coexisting branches: the model has no exact flow to shoot (shooting needs constant-stiffness "
    "backlash or contact-stop laws), so each branch is cut at its first jump in the outputs instead "
    "of its first hop on the exact flow, and its changes of stability are harmonic balance's, "
    "listed unconfirmed"
)
#: The owner of a matrix model's outputs (no links): ``model.<quantity> [unit]``.
MATRIX_OWNER = "model"


def metric_links(res: SweepResult, usable) -> pd.DataFrame:
    """The outputs of a model built from matrices (no links): its first law's metrics, as
    ``model.<quantity> [SI unit]`` columns, NaN where not ``usable``.

    Parameters
    ----------
    res : SweepResult
        The points.
    usable : ndarray of bool
        Per point: whether it has outputs.

    Returns
    -------
    pandas.DataFrame
    """
    ok = np.asarray(usable, dtype=bool)
    data = {
        f"{MATRIX_OWNER}.{name} [{unit}]": np.where(ok, np.asarray(res.metrics[name], dtype=float), np.nan)
        for name, unit in METRIC_UNITS.items()
        if unit
    }
    return pd.DataFrame(data)


def _outputs(model, branch: SweepResult) -> pd.DataFrame:
    """Every output at every converged row of a branch (stable or not)."""
    usable = np.asarray(branch.converged, dtype=bool)
    return link_rows(model, branch, usable) if model is not None else metric_links(branch, usable)


def _cut_at_first_jump(branch: SweepResult, outputs: pd.DataFrame, skip=()) -> SweepResult:
    """The branch without its rows past the first jump in its outputs (but ``skip``, the
    linear bearings'), each direction away from the orbit found (the stand-in for the
    exact flow's hop test)."""
    cols = [c for c in outputs.columns if c not in skip and _jumps_on(c)]
    values = {c: outputs[c].to_numpy(float) for c in cols}
    if not values:
        return branch
    whole = replace(branch, no_stable=np.zeros(len(branch), dtype=bool))  # a turn unstable is no jump
    drop = np.zeros(len(branch), dtype=bool)
    for jump in whole.jumps_of(values):
        sign = 1.0 if jump.direction == "up" else -1.0
        past = (branch.direction == jump.direction) & (sign * (branch.omega - jump.omega_from) > 0)
        if not np.any(drop & (branch.direction == jump.direction)):  # the first jump only
            drop |= past
    return without_rows(branch, drop)


def _verdict_changes(branch: SweepResult) -> list[tuple[str, str, float, float]]:
    """(direction, kind, ω of the stable row, ω of the unstable row) where the settled
    verdict changes between consecutive converged rows (kind from the unstable row's
    dominant multiplier)."""
    out = []
    ok = branch.converged & branch.stability_known & branch.verdict_converged
    for d in dict.fromkeys(branch.direction.tolist()):
        idx = np.nonzero((branch.direction == d) & ok)[0]
        for i, j in zip(idx[:-1], idx[1:], strict=True):
            if branch.stable[i] == branch.stable[j]:
                continue
            s, u = (i, j) if branch.stable[i] else (j, i)
            mu = complex(branch.dominant_multiplier[u])
            kind = (
                "Neimark-Sacker"
                if abs(mu.imag) > 1e-6 * abs(mu)
                else ("period doubling" if mu.real < 0 else "fold")
            )
            out.append((d, kind, float(branch.omega[s]), float(branch.omega[u])))
    return out


def _bracket(branch: SweepResult, d: str, w: float) -> tuple[float, float]:
    """The converged rows of direction ``d`` on either side of ω (ω itself past the last)."""
    rows = np.asarray(branch.omega)[(branch.direction == d) & np.asarray(branch.converged, dtype=bool)]
    below, above = rows[rows <= w], rows[rows >= w]
    return (float(below.max()) if below.size else w, float(above.min()) if above.size else w)


def bifurcations(reduced: ReducedModel, branch: SweepResult) -> tuple[Bifurcation, ...]:
    """The bifurcations of a coexisting branch: located on the exact flow where the model
    is shootable (confirmed), and every change of verdict between rows that none of those
    lies in (unconfirmed; on a model that cannot be shot, all of them).

    Parameters
    ----------
    reduced : ReducedModel
        The model of the branch.
    branch : SweepResult
        A branch with settled verdicts.

    Returns
    -------
    tuple of Bifurcation
    """
    found = []
    for d, kind, w in locate_bifurcations(reduced, branch) if shootable(reduced) else []:
        lo, hi = _bracket(branch, d, w)
        found.append(Bifurcation(d, kind, float(w), lo, hi, True))
    for d, kind, ws, wu in _verdict_changes(branch):
        lo, hi = min(ws, wu), max(ws, wu)
        if not any(f.direction == d and lo <= f.omega <= hi for f in found):
            found.append(Bifurcation(d, kind, 0.5 * (ws + wu), lo, hi, False))
    return tuple(found)


def with_coexisting(
    res: LinkSweepResult,
    reduced: ReducedModel,
    *,
    model=None,
    ladder=None,
    jumps=None,
    progress=None,
    locate_progress=None,
) -> LinkSweepResult:
    """``res`` with its coexisting branches (module notes): the period-1 rows of the sweep
    searched beside at its jumps, each branch's outputs and bifurcations.

    Parameters
    ----------
    res : LinkSweepResult
        A sweep with stability.
    reduced : ReducedModel
        Its period-1 model.
    model : LinkModel, optional
        The link model (its receptance prepared for the branches' H, its links' outputs);
        None: a model built from matrices (:func:`metric_links`).
    ladder : sequence of int, optional
        The rungs of H of the sweep (a link model's: the ladder times its ``top_order``).
    jumps : list of Jump, optional
        The jumps searched beside; default ``res.result.jumps()``.
    progress, locate_progress : callable, optional
        ``progress(i, n)`` per frequency searched at, ``locate_progress(i, n)`` per branch
        whose bifurcations are located.

    Returns
    -------
    LinkSweepResult
        With :attr:`~LinkSweepResult.coexisting` (and its note on a model that cannot be shot).
    """
    r = res.result
    p1 = replace(r, converged=r.converged & (np.asarray(r.period) == 1))  # period-1 rows only
    rungs = {} if ladder is None else {"ladder": ladder}
    H = next_harmonics(next_harmonics(int(r.H), **rungs), **rungs)
    if model is not None:
        top = float(np.max(np.abs(r.omega)))
        model.receptance.prepare(next_harmonics(H, **rungs) * top)  # the branches' check rung
        model.receptance.prepare_stability(top)
    found = coexisting_branches(reduced, p1, H=H, ladder=ladder, jumps=jumps, progress=progress)
    exact = shootable(reduced)
    out = []
    for k, branch in enumerate(found):
        if locate_progress is not None:
            locate_progress(k, len(found))
        if not exact:
            skip = bearing_columns(model) if model is not None else ()
            branch = _cut_at_first_jump(branch, _outputs(model, branch), skip)
        name = f"coexisting {k + 1}"
        out.append(CoexistingBranch(name, branch, _outputs(model, branch), bifurcations(reduced, branch)))
    if locate_progress is not None and found:
        locate_progress(len(found), len(found))
    return replace(res, coexisting=tuple(out), coexisting_note="" if exact else NO_EXACT_FLOW)

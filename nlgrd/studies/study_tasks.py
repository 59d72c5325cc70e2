"""A study's tasks: one sweep each, specified by plain data and run anywhere.

A :class:`TaskSpec` holds everything a task needs as picklable plain data (the changed
model file's content, the analysis, the parameters), so a Dask worker in another
process or on another machine rebuilds the model itself: no closure, no cache and no
open file crosses a process boundary. Its :attr:`~TaskSpec.key` is a SHA-256 of the
model data, the analysis, the content of any LSTE or stiffness file the model reads, and the nlgrd
version: results stored under it are never mixed with those of another model or
library version.

:func:`run_task` runs the sweep with one BLAS thread (the same arithmetic in a worker
as in the calling process) and returns the per-point table and a one-row summary
(:func:`summarise`); an exception inside the task becomes the task's recorded error.
"""

from __future__ import annotations

import hashlib
import json
import math
import os
import time
import traceback
import warnings
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pandas as pd

import nlgrd
from nlgrd.errors import ModelError
from nlgrd.studies.study_file import Study
from nlgrd.threads import single_blas_thread

__all__ = ["SummaryColumns", "TaskSpec", "run_task", "summarise", "task_specs"]

#: Columns of a summary row, in order (those a model lacks are NaN).
SUMMARY_COLUMNS = (
    "dslr_peak [-]",
    "dte_rms_peak [um]",
    "mesh_force_peak [N]",
    "resonance",
    "jump_up",
    "jump_down",
    "jump_width",
    "jumps",
    "bearing_force_max [N]",
    "points",
    "failed_points",
    "no_stable_points",
    "H_max",
)


@dataclass(frozen=True)
class TaskSpec:
    """One task of a study: a sweep of the base model with some values changed.

    Parameters
    ----------
    index : int
        Position in the study (grid order).
    parameters : dict
        Axis column name -> value.
    model_data : dict
        The changed model file's content.
    model_file : str
        The base model file (relative paths in the model are taken from its folder).
    analysis : dict
        :meth:`nlgrd.studies.study_file.Analysis.as_dict`.
    key : str
        SHA-256 hex digest naming the result (see the module docstring).
    """

    index: int
    parameters: dict
    model_data: dict
    model_file: str
    analysis: dict
    key: str = field(default="")


def _canonical(obj: Any) -> str:
    return json.dumps(obj, sort_keys=True, separators=(",", ":"), allow_nan=False)


def _file_digests(data: dict, model_file: str) -> dict[str, str]:
    """SHA-256 of every LSTE and stiffness file the model data names (relative to the model file)."""
    out = {}
    base = os.path.dirname(os.path.abspath(model_file))
    for g in data.get("gear_pairs", []) or []:
        for name in (g.get(k) for k in ("lste_file", "stiffness_file")) if isinstance(g, dict) else ():
            if not isinstance(name, str):
                continue
            path = os.path.join(base, name)
            try:
                with open(path, "rb") as fh:
                    out[name] = hashlib.sha256(fh.read()).hexdigest()
            except OSError:
                out[name] = "missing"
    return out


def task_key(model_data: dict, model_file: str, analysis: dict) -> str:
    """The result key of a task (see the module docstring).

    Parameters
    ----------
    model_data : dict
        The task's model file content.
    model_file : str
        The base model file (for LSTE and stiffness files named relative to it).
    analysis : dict
        The analysis.

    Returns
    -------
    str
        64 hex digits.
    """
    content = {
        "model": model_data,
        "files": _file_digests(model_data, model_file),
        "analysis": analysis,
        "nlgrd": nlgrd.__version__,
    }
    return hashlib.sha256(_canonical(content).encode()).hexdigest()


def task_specs(study: Study) -> list[TaskSpec]:
    """Every task of ``study``, in grid order.

    Parameters
    ----------
    study : Study

    Returns
    -------
    list of TaskSpec
    """
    analysis = study.analysis.as_dict()
    out = []
    for i, params in enumerate(study.parameter_sets()):
        data = study.model_data(params)
        out.append(
            TaskSpec(i, params, data, study.model_file, analysis, task_key(data, study.model_file, analysis))
        )
    return out


# ----------------------------------------------------------------------------- running


@dataclass(frozen=True)
class SummaryColumns:
    """Which columns of a sweep's table hold the summarised outputs, read from the model's
    typed outputs (its gear meshes, bearings and links), not from column-name patterns.

    Attributes
    ----------
    dslr : list of str
        Dynamic-to-static load ratio columns [-], one per mesh.
    dte_rms : list of tuple (str, float)
        RMS DTE columns, each with its factor to µm (1 for ``[um]``, 1e6 for ``[m]``).
    mesh_force : list of str
        Largest mesh force columns [N].
    bearing_force : list of str
        Largest bearing (or bearing clearance) force columns [N].
    """

    dslr: list = field(default_factory=list)
    dte_rms: list = field(default_factory=list)
    mesh_force: list = field(default_factory=list)
    bearing_force: list = field(default_factory=list)

    @classmethod
    def of(cls, outputs) -> SummaryColumns:
        """The summary columns among a table's typed outputs: each gear mesh's DSLR, RMS
        DTE (with its factor to µm) and largest force; every bearing's and bearing
        clearance's largest force.

        Parameters
        ----------
        outputs : sequence of nlgrd.units.OutputColumn
            The table's outputs (``output_columns`` of a link model).

        Returns
        -------
        SummaryColumns
        """
        mesh = [c for c in outputs if c.kind == "gear mesh"]
        return cls(
            dslr=[c.column for c in mesh if c.quantity == "dslr"],
            dte_rms=[(c.column, c.factor_to("um")) for c in mesh if c.quantity == "dte_rms"],
            mesh_force=[c.column for c in mesh if c.quantity == "force_max"],
            bearing_force=[
                c.column
                for c in outputs
                if c.kind in ("bearing", "bearing clearance") and c.quantity == "force_max"
            ],
        )


def _link_columns(model) -> SummaryColumns:
    """The summary columns of a link sweep's table, from the model's typed outputs
    (:func:`~nlgrd.nonlinear.results.link_results.output_columns`, in their written units:
    :meth:`nlgrd.units.OutputColumn.written`): the linear bearings' first, then each
    link's in the model's order."""
    from nlgrd.nonlinear.results.link_results import output_columns

    outputs = [c.written() for c in output_columns(model)]  # as the table writes them
    return SummaryColumns.of(
        [c for c in outputs if c.kind == "bearing"] + [c for c in outputs if c.kind != "bearing"]
    )


def _sweep_frame(system, analysis: dict) -> tuple[pd.DataFrame, list, str, float, SummaryColumns]:
    """Run the analysis on ``system``: (points, jumps, x column, x per rad/s, summary columns).

    One flow for every model, one mesh too: the link model
    (:func:`~nlgrd.nonlinear.models.link_model.build_link_model`) on its frequency plan,
    swept by :func:`~nlgrd.nonlinear.models.link_model.link_sweep` on the base frequency (a
    gear pair whose errors repeat every N mesh periods: the mesh frequency / N, H in
    harmonics of it) and its gaps answered as ``nlgrd sweep`` answers them.
    """
    from nlgrd.nonlinear.models.link_model import build_link_model, link_sweep

    values = np.linspace(analysis["start"], analysis["stop"], analysis["count"])
    rpm = analysis["unit"] == "rpm"
    model = build_link_model(system)
    per_rad = 30 / math.pi * model.receptance.plan.speed_per_base if rpm else 1 / (2 * math.pi)
    res = link_sweep(  # period "auto": one question of every model
        model,
        values / per_rad,
        H=analysis["harmonics"],
        rtol=analysis["tolerance"],
        period="auto",
        directions=analysis["direction"],
        stability=analysis["stability"],
    )
    res = _time_answers(res, model, analysis)
    frame = res.to_frame()
    x_col = "shaft_speed [rpm]" if rpm else "base_frequency [Hz]"
    if rpm:
        frame.insert(1, x_col, frame["base_frequency [Hz]"] * 2 * math.pi * per_rad)
    return frame, res.jumps(), x_col, per_rad, _link_columns(model)


def _time_answers(res, model, analysis: dict):
    """``res`` with its points without a stable periodic orbit answered by time integration
    (:func:`nlgrd.timedomain.sweep_answers.answer_sweep`, the rule ``nlgrd sweep`` follows),
    when the analysis has stability and ``time_domain``; ``model`` the link model."""
    from nlgrd.timedomain.sweep_answers import answer_sweep

    return answer_sweep(
        res,
        model=model,
        period="auto",
        stability=analysis["stability"],
        time_domain=analysis.get("time_domain", True),
        rtol=analysis["tolerance"],
    )


def _peak(frame: pd.DataFrame, columns: list, scales: list | None = None) -> float:
    """Largest finite value of ``columns`` (each times its scale); NaN when there is none."""
    scales = [1.0] * len(columns) if scales is None else scales
    missing = [c for c in columns if c not in frame]
    if missing:
        raise KeyError(f"summary columns {missing} are not in the sweep's table")
    if not columns:
        return math.nan
    v = frame[list(columns)].astype(float).to_numpy() * np.asarray(scales, dtype=float)
    return float(np.nanmax(v)) if np.isfinite(v).any() else math.nan


def summarise(
    frame: pd.DataFrame, jumps: list, x_col: str, per_rad: float, columns: SummaryColumns
) -> dict[str, Any]:
    """The summary row of one sweep (:data:`SUMMARY_COLUMNS`, frequencies in the x unit).

    The resonance is the speed (frequency) of the largest DSLR (or RMS DTE) of the sweep.
    The main jump of a direction is its jump nearest to that direction's peak: the jump
    off or onto the resonance, not those of superharmonic resonances; its place is the
    midpoint of the two points. The jump width is up minus down: the band of coexisting
    responses of that resonance.

    Parameters
    ----------
    frame : pandas.DataFrame
        The sweep's points.
    jumps : list of Jump
        Its jumps.
    x_col : str
        The x column (speed [rpm] or frequency [Hz]).
    per_rad : float
        x units per rad/s.
    columns : SummaryColumns
        Which columns hold DSLR, RMS DTE, mesh and bearing forces (from the model).

    Returns
    -------
    dict
    """
    unit = x_col[x_col.index("[") :]
    dslr_cols = columns.dslr
    dte_cols = [c for c, _ in columns.dte_rms]
    peak_col = dslr_cols[0] if dslr_cols else (dte_cols[0] if dte_cols else None)
    resonance = math.nan
    peaks = {}
    if peak_col is not None and frame[peak_col].notna().any():
        resonance = float(frame.loc[frame[peak_col].astype(float).idxmax(), x_col])
        for d, part in frame.groupby("direction"):
            if part[peak_col].notna().any():
                peaks[d] = float(part.loc[part[peak_col].astype(float).idxmax(), x_col])
    main = {}
    for j in jumps:
        at = 0.5 * (j.omega_from + j.omega_to) * per_rad
        distance = abs(at - peaks.get(j.direction, resonance))
        if j.direction not in main or distance < main[j.direction][0]:
            main[j.direction] = (distance, at)
    up = main.get("up", (0, math.nan))[1]
    down = main.get("down", (0, math.nan))[1]
    converged = frame["converged"].astype(bool)
    # a stable periodic orbit of any period answers; anything else has none
    periodic = frame["response"].astype("string").fillna("").str.fullmatch(r"periodic|period \d+")
    no_stable = ~periodic.astype(bool) & converged
    return {
        "dslr_peak [-]": _peak(frame, dslr_cols),
        "dte_rms_peak [um]": _peak(frame, dte_cols, [f for _, f in columns.dte_rms]),
        "mesh_force_peak [N]": _peak(frame, columns.mesh_force),
        f"resonance {unit}": resonance,
        f"jump_up {unit}": up,
        f"jump_down {unit}": down,
        f"jump_width {unit}": up - down,
        "jumps": len(jumps),
        "bearing_force_max [N]": _peak(frame, columns.bearing_force),
        "points": len(frame),
        "failed_points": int((~converged).sum()),
        "no_stable_points": int(no_stable.sum()),
        "H_max": int(frame["H"].max()) if frame["H"].notna().any() else 0,
    }


@single_blas_thread
def run_task(spec: TaskSpec) -> dict[str, Any]:
    """Run one task: build the model, sweep, summarise.

    Parameters
    ----------
    spec : TaskSpec

    Returns
    -------
    dict
        ``key``, ``index``, ``points`` (DataFrame or None), ``summary`` (dict or None),
        ``error`` (one line, or None), ``warnings`` (list of str), ``seconds`` (the
        task's own time on its worker [s]).
    """
    from nlgrd.io.model_file import model_from_file_data

    t0 = time.perf_counter()
    out: dict[str, Any] = {"key": spec.key, "index": spec.index, "points": None, "summary": None}
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            system = model_from_file_data(spec.model_data, spec.model_file)
            frame, jumps, x_col, per_rad, columns = _sweep_frame(system, spec.analysis)
            out["summary"] = summarise(frame, jumps, x_col, per_rad, columns)
            out["points"] = frame
            out["error"] = None
        except Exception as err:  # recorded: the study goes on
            last = traceback.extract_tb(err.__traceback__)[-1]
            if isinstance(err, ModelError) and err.file is None:  # the model is the culprit
                err = err.within(file=spec.model_file)
            where = f" ({os.path.basename(last.filename)}:{last.lineno})"
            out["error"] = f"{type(err).__name__}: {' '.join(str(err).split())}{where}"
    out["warnings"] = sorted({" ".join(str(w.message).split()) for w in caught})
    out["seconds"] = time.perf_counter() - t0
    return out

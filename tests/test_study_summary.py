"""A study's summary row against one sweep run by hand (issue 33): units and forces.

Two studies of one task each, run in this process (``run_task``, no Dask):

- ``two_shaft.toml``, whose bearings have names: one mesh, on the link engine as every
  model, bearing columns ``<name>.force_max [N]``;
- the same model with a bearing clearance at the pinion's free-end bearing (written into
  a temporary model file), columns ``<link>.<quantity> [unit]``.

The hand sweep is the library's own call with the study's analysis; the summary must be
the maximum over the sweep of the typed outputs (each link's ``metrics`` recomputed from
the harmonics, the DTE in metres times 1e6, every linear bearing's recovered force), not
of whatever columns match a pattern. The
same arithmetic in the same process (one BLAS thread both times): 1e-12.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from nlgrd.io.model_file import load_model
from nlgrd.studies.study_file import load_study
from nlgrd.studies.study_tasks import run_task, task_specs
from nlgrd.threads import single_blas_thread

ROOT = Path(__file__).resolve().parents[1]
TWO_SHAFT = ROOT / "data" / "models" / "two_shaft.toml"
RTOL = 1e-12

#: A radial clearance of 5 µm at the pinion's free-end bearing (node 8): the static mesh
#: load (~2.3 kN on 1.5e8 N/m bearings, ~1e-5 m) keeps the journal on it, so its force
#: is not zero.
CLEARANCE = """
[[bearing_clearances]]
name = "B1"
shaft = 0
node = 8
clearance = 5e-6
stiffness = 1.0e8
exponent = 1.0
"""


def study_text(model: Path) -> str:
    return f"""version = 1
name = "summary check"
model = "{model.as_posix()}"
[analysis]
rpm = [6000.0, 12000.0, 6]
direction = "up"
harmonics = 5
stability = false
[[axes]]
key = "gear_pairs[0].damping_ratio"
values = [0.05]
"""


def one_task(tmp_path: Path, model: Path) -> tuple[dict, dict]:
    path = tmp_path / "study.toml"
    path.write_text(study_text(model))
    (spec,) = task_specs(load_study(path))
    out = run_task(spec)
    assert out["error"] is None, out["error"]
    return out["summary"], spec


def close(a: float, b: float) -> bool:
    return math.isfinite(a) and math.isfinite(b) and abs(a - b) <= RTOL * abs(b)


def hand_sweep(spec) -> tuple:
    """The study's analysis run by hand on the link model of its model (what every study
    runs, one mesh too), and per point the mesh's RMS DTE [m] and largest force [N] from
    its own ``metrics``, every clearance's largest force and the linear bearings' largest
    force recovered from the harmonics (the recovery checked against the FE model in
    tests/test_engine_equivalence.py)."""
    from nlgrd.io.model_file import model_from_file_data
    from nlgrd.nonlinear.links.contract import BearingClearance, GearMeshLink
    from nlgrd.nonlinear.models.link_model import build_link_model, link_sweep
    from nlgrd.nonlinear.results.bearing_loads import link_bearing_outputs

    system = model_from_file_data(spec.model_data, spec.model_file)
    a = spec.analysis
    model = build_link_model(system)
    per_rad = 30 / math.pi * model.receptance.plan.speed_per_base
    omegas = np.linspace(a["start"], a["stop"], a["count"]) / per_rad
    res = single_blas_thread(link_sweep)(
        model, omegas, H=a["harmonics"], rtol=a["tolerance"], directions=a["direction"], stability=False
    ).result
    assert np.asarray(res.converged, dtype=bool).all()
    (mesh,) = [lk for lk in model.links if isinstance(lk, GearMeshLink)]
    clears = [lk for lk in model.links if isinstance(lk, BearingClearance)]
    dte, force, mesh_force, linear = [], [], [], []
    for z, w in zip(res.harmonics, res.omega, strict=True):
        m = mesh.metrics(model.link_harmonics(z, mesh.name), w)
        dte.append(m["dte_rms [m]"])
        mesh_force.append(m["force_max [N]"])
        force += [c.metrics(model.link_harmonics(z, c.name), w)["force_max [N]"] for c in clears]
        bearings = link_bearing_outputs(model, z, w)
        linear.append(max(v for k, v in bearings.items() if k.endswith(".force_max [N]")))
    return system, dte, force, mesh_force, linear


def test_named_bearings_summary_equals_the_hand_sweep(tmp_path):
    """Bearings with names (two_shaft.toml, one mesh, on the link engine as every model):
    ``bearing_force_max`` is the largest bearing force of the sweep (it was NaN: the
    summary looked for columns named ``bearing ...``), ``dte_rms_peak [um]`` the largest
    RMS DTE in µm, each recomputed here from the harmonics."""
    summary, spec = one_task(tmp_path, TWO_SHAFT)
    system, dte, _, mesh_force, linear = hand_sweep(spec)
    assert all(b.name for b in system.bearings)
    assert max(linear) > 100.0  # the bearings carry the mesh load (~2.3 kN over two bearings)
    assert close(summary["dte_rms_peak [um]"], 1e6 * max(dte)), (summary["dte_rms_peak [um]"], max(dte))
    assert summary["dte_rms_peak [um]"] > 0.01  # µm, not m
    assert close(summary["bearing_force_max [N]"], max(linear)), (summary["bearing_force_max [N]"], linear)
    assert close(summary["mesh_force_peak [N]"], max(mesh_force))


def test_link_model_summary_equals_the_hand_sweep(tmp_path):
    """A link model (two_shaft.toml with a bearing clearance): ``dte_rms_peak [um]`` is the
    mesh's largest RMS DTE in µm (it was in metres: 1e6 too small) and
    ``bearing_force_max`` the largest of the clearance's contact force and the linear
    bearings' forces (it was the clearance's only), each recomputed here from the harmonics
    (the link's own ``metrics``; the bearings' recovery, checked against the single path in
    tests/test_engine_equivalence.py)."""
    from nlgrd.nonlinear.models.link_model import needs_links

    model_file = tmp_path / "two_shaft_clearance.toml"
    model_file.write_text(TWO_SHAFT.read_text() + CLEARANCE)
    assert needs_links(load_model(model_file))
    summary, spec = one_task(tmp_path, model_file)
    _, dte, force, mesh_force, linear = hand_sweep(spec)
    assert max(force) > 0.0  # the journal is on the clearance
    assert close(summary["dte_rms_peak [um]"], 1e6 * max(dte)), (summary["dte_rms_peak [um]"], max(dte))
    assert summary["dte_rms_peak [um]"] > 0.01  # µm, not m
    top = max(max(force), max(linear))  # the clearance's contact force or a linear bearing's
    assert max(linear) > max(force)  # the linear bearings carry most of the load here
    assert close(summary["bearing_force_max [N]"], top), (summary["bearing_force_max [N]"], top)
    assert close(summary["mesh_force_peak [N]"], max(mesh_force))


@pytest.mark.parametrize("missing", ["dslr", "bearing_force"])
def test_a_summary_column_missing_from_the_table_is_an_error(missing):
    """A typed column that is not in the table raises (a renamed column must not turn a
    summary value into NaN silently)."""
    import pandas as pd

    from nlgrd.studies.study_tasks import SummaryColumns, summarise

    frame = pd.DataFrame(
        {"x [Hz]": [1.0, 2.0], "direction": ["up", "up"], "converged": [True, True]}
        | {"response": ["periodic"] * 2, "H": [5, 5], "dslr [-]": [1.0, 2.0], "b force_max [N]": [3.0, 4.0]}
    )
    cols = SummaryColumns(dslr=["dslr [-]"], bearing_force=["b force_max [N]"])
    row = summarise(frame, [], "x [Hz]", 1.0, cols)
    assert row["dslr_peak [-]"] == 2.0 and row["bearing_force_max [N]"] == 4.0
    bad = SummaryColumns(**{**cols.__dict__, missing: ["nope [-]"]})
    with pytest.raises(KeyError, match="nope"):
        summarise(frame, [], "x [Hz]", 1.0, bad)


def test_a_study_asks_every_model_for_period_auto(tmp_path, monkeypatch):
    """The same study file answers the same question on both paths (issue 33: the link
    path's sweep defaulted to period 1, the single mesh's to "auto"): the link model's
    sweep is asked for ``period="auto"``, the default of ``nlgrd.sweep``."""
    import inspect

    import nlgrd.nonlinear.models.link_model as link_model
    from nlgrd.analyses import sweep

    asked = {}
    real = link_model.link_sweep

    def spy(*args, **kwargs):
        asked.update(kwargs)
        return real(*args, **kwargs)

    monkeypatch.setattr(link_model, "link_sweep", spy)
    for name, text in (("one_mesh", ""), ("clearance", CLEARANCE)):  # one mesh and a clearance
        asked.clear()
        model_file = tmp_path / f"two_shaft_{name}.toml"
        model_file.write_text(TWO_SHAFT.read_text() + text)
        one_task(tmp_path, model_file)
        assert asked["period"] == inspect.signature(sweep).parameters["period"].default == "auto"


def test_a_period_two_answer_is_not_counted_as_no_stable_response():
    """``no_stable_points`` counts converged points without a stable periodic orbit of any
    period: a period-2 answer is a stable response (it was counted as none), a
    quasi-periodic or "no stable response" point is not, an unconverged point is a failure."""
    import pandas as pd

    from nlgrd.studies.study_tasks import SummaryColumns, summarise

    frame = pd.DataFrame(
        {
            "base_frequency [Hz]": [1.0, 2.0, 3.0, 4.0, 5.0],
            "direction": ["up"] * 5,
            "converged": [True, True, True, True, False],
            "response": pd.array(
                ["periodic", "period 2", "quasi-periodic", "no stable response", pd.NA], dtype="string"
            ),
            "H": [9, 9, 9, 9, pd.NA],
            "dslr [-]": [1.0, 1.2, np.nan, np.nan, np.nan],
        }
    )
    columns = SummaryColumns(dslr=["dslr [-]"], dte_rms=[], mesh_force=[], bearing_force=[])
    row = summarise(frame, [], "base_frequency [Hz]", 1.0, columns)
    assert row["no_stable_points"] == 2 and row["failed_points"] == 1


def test_a_study_answers_its_gaps_in_the_time_domain(tmp_path):
    """Issue 35 item 4: a study's sweep gives every speed a response as ``nlgrd sweep`` does.
    K&B at 3500-3600 Hz (tests/test_time_answer.py: the mesh-periodic orbit is lost to a
    complex pair at 3550 and 3600 Hz, the time answers there checked against 4x longer
    integrations): with ``time_domain`` (the default) the summary's peak RMS DTE includes
    the rattling answered in the time domain (2.7 µm against the one periodic point's
    1.2 µm); ``time_domain = false`` leaves the gaps, as before."""
    kb = ROOT / "data" / "case_studies" / "kahraman_blankenship.toml"
    peaks = {}
    for on in (True, False):
        text = study_text(kb).replace("rpm = [6000.0, 12000.0, 6]", "hz = [3500.0, 3600.0, 3]")
        text = text.replace("stability = false", f"stability = true\ntime_domain = {str(on).lower()}")
        path = tmp_path / f"study_{on}.toml"
        path.write_text(text)
        (spec,) = task_specs(load_study(path))
        out = run_task(spec)
        assert out["error"] is None, out["error"]
        assert out["summary"]["no_stable_points"] == 2  # no stable periodic orbit at either
        peaks[on] = out["summary"]["dte_rms_peak [um]"]
    assert math.isfinite(peaks[False]) and peaks[True] > 1.5 * peaks[False], peaks

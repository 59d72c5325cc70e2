"""Issue 33 item 5: one result family. Every public class of nlgrd named ``*Result`` or
``*Response`` (found by walking the package) has ``to_frame()`` and ``plot(ax=None)``, and
both work on a small case; the results added to the family (Floquet multipliers, bearing
loads, tori, the orbits of a search) are checked against independent numbers."""

from __future__ import annotations

import importlib
import inspect
import pkgutil
import re
from pathlib import Path

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402
import pytest  # noqa: E402

import nlgrd  # noqa: E402
from nlgrd.errors import ModelError  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
TWO_SHAFT = ROOT / "data" / "models" / "two_shaft.toml"
RUB = ROOT / "data" / "models" / "rub_rotor.toml"
LSTE = np.array([0.0, 1.24e-6, 0.0, 0.50e-6, 0.30e-6, 0.10e-6, -0.05e-6])


def result_classes() -> dict[str, type]:
    """Public classes named ``*Result``/``*Response`` defined in a module of nlgrd."""
    found = {}
    for info in pkgutil.walk_packages(nlgrd.__path__, "nlgrd."):
        if info.name.endswith("__main__"):  # runs the command on import
            continue
        mod = importlib.import_module(info.name)
        for name, cls in vars(mod).items():
            if (
                inspect.isclass(cls)
                and cls.__module__ == mod.__name__
                and re.fullmatch(r"[A-Z]\w*(Result|Response)", name)
            ):
                found[f"{mod.__name__}.{name}"] = cls
    return found


# --- small cases, one per result class (keyed by the class's full name) ------------------


def _sdof():
    from nlgrd.nonlinear.models.sdof import SDOFGearPair

    return SDOFGearPair(0.261, 0.2587e9, 50e-6, 2295.0, LSTE, damping_ratio=0.02)


def _floquet():
    """One mass (1 kg) on a 1e6 N/m spring and a mesh of 3e6 N/m always in contact,
    damped 20 N s/m: linear, so its multipliers over T = 2π/ω are exp(λ T) of its
    eigenvalues λ = -ζω_n ± iω_d."""
    from nlgrd.nonlinear.laws.force_laws import ParametricMesh
    from nlgrd.nonlinear.reduction.state_space import LinearStateSpace
    from nlgrd.nonlinear.stability.floquet import floquet_analysis

    law = ParametricMesh(3e6, 0.0, stiffness_variation=np.array([1.0]))
    ss = LinearStateSpace(np.eye(1), np.array([[20.0]]), np.array([[1e6]]), np.ones((1, 1)))
    return floquet_analysis(ss, [law], np.array([[6e-6]]), OMEGA_FLOQUET, method="dense", deflate=False)


OMEGA_FLOQUET = 300.0


def _torus():
    """Three speeds, tori at the first and last (the arrays as torus_sweep packs them)."""
    from nlgrd.nonlinear.tracing.torus_outputs import CHECKED, TORUS_OUTPUTS
    from nlgrd.nonlinear.tracing.torus_sweep import TorusResult

    n, m = 3, len(TORUS_OUTPUTS)
    conv = np.array([True, False, True])
    outputs = np.where(
        conv[:, None], np.arange(1.0, m + 1)[None, :] * np.array([[1e-6], [1e-6], [2e-6]]), np.nan
    )
    return TorusResult(
        omega=2 * np.pi * np.array([1000.0, 1010.0, 1020.0]),
        rpm=np.array([2400.0, 2424.0, 2448.0]),
        converged=conv,
        outputs=outputs,
        change=np.full((n, len(CHECKED)), 1e-4),
        multiplier=np.full(n, 1.01 + 0.2j),
        residual=np.full(n, 1e-11),
        iterations=np.full(n, 5),
        seconds=np.ones(n),
        H=5,
        H2=4,
        bearing_force_max=np.full((n, 1), 10.0),
        bearing_names=["B1"],
        solutions=[None] * n,
    )


def _orbits():
    """The single-DOF impact pair of tests/test_orbit_search.py at 2.6 ω_n: a stable
    period-1 orbit and a stable and an unstable period-3 orbit."""
    from nlgrd.nonlinear.models.sdof import SDOFGearPair
    from nlgrd.nonlinear.tracing.orbit_search import search_orbits

    k, m, b = 1e8, 0.1, 50e-6
    pair = SDOFGearPair(m, k, b, k * 10e-6, np.array([0.0, 30e-6, 0.0]), 0.01)
    return search_orbits(lambda nu: pair.subharmonic(nu).reduced_model(), 2.6 * np.sqrt(k / m), 9, (1, 3))


def _continuation():
    from nlgrd.nonlinear.tracing.continuation import continuation

    sd = _sdof()
    return continuation(sd.reduced_model(), 0.7 * sd.natural_frequency, 0.75 * sd.natural_frequency, 5)


def _lste():
    from nlgrd.gear.geometry import GearGeometry
    from nlgrd.gear.transmission_error import loaded_static_transmission_error

    g = GearGeometry(
        teeth_pinion=25,
        teeth_gear=25,
        module=4e-3,
        face_width=15e-3,
        tip_diameter_pinion=0.108,
        tip_diameter_gear=0.108,
        bore_diameter_pinion=0.040,
        bore_diameter_gear=0.040,
    )
    return loaded_static_transmission_error(g, 1000.0, points_per_cycle=8)


def _two_dof():
    from nlgrd.rotor.frequency_response import LinearModel

    M = np.diag([2.0, 1.0])
    K = np.array([[6e5, -2e5], [-2e5, 2e5]])
    C = np.array([[40.0, -10.0], [-10.0, 10.0]])
    return LinearModel.from_matrices(M, K, C)


def _frequency_response():
    from nlgrd.rotor.frequency_response import frequency_response

    return frequency_response(_two_dof(), np.linspace(1.0, 1500.0, 20), inputs=[0, 1], outputs=[0, 1])


def _static():
    from nlgrd.rotor.frequency_response import static_deflection

    return static_deflection(nlgrd.load(TWO_SHAFT), {(0, 1, "uy"): 10.0})


def _sdof_time():
    from nlgrd.timedomain.sdof import integrate

    sd = _sdof()
    return integrate(sd, 0.8 * sd.natural_frequency, tol=1e-6)


def _link_time():
    from nlgrd.nonlinear.models.link_model import build_link_model
    from nlgrd.timedomain.links import link_time_response

    model = build_link_model(nlgrd.load(RUB))
    return link_time_response(model, 2 * np.pi * 40.0, steps_per_period=64, tol=1e-4, max_periods=200)


def _ramp():
    from nlgrd.timedomain.run_down import RampResult

    w = 2 * np.pi * np.array([3000.0, 2990.0, 2980.0])
    mesh = {
        "dte_mean [m]": np.full(3, 1e-6),
        "dte_rms [m]": np.array([2e-6, 3e-6, 1e-6]),
        "elastic_force_max [N]": np.full(3, 900.0),
        "contact_loss_fraction [-]": np.zeros(3),
    }
    return RampResult(
        w, np.array([0.0, 1e-3, 2e-3]), {"mesh0": mesh}, {"mesh0": "gear mesh"}, 100.0, 1e-5, 1 / 25
    )


CASES = {
    "nlgrd.gear.transmission_error.LSTEResult": _lste,
    "nlgrd.nonlinear.results.link_results.LinkSweepResult": lambda: nlgrd.sweep(
        nlgrd.load(RUB), rpm=[2000.0, 3000.0], H=5, directions="up"
    ),
    "nlgrd.nonlinear.results.link_results.LinkContinuationResult": lambda: nlgrd.continuation(
        nlgrd.load(RUB), rpm=(2000.0, 2100.0), H=5
    ),
    "nlgrd.nonlinear.results.sweep_results.SweepResult": lambda: _sdof_sweep(),
    "nlgrd.nonlinear.results.sweep_results.ContinuationResult": _continuation,
    "nlgrd.nonlinear.stability.floquet.FloquetResult": _floquet,
    "nlgrd.nonlinear.tracing.orbit_search.OrbitSearchResult": _orbits,
    "nlgrd.nonlinear.tracing.torus_sweep.TorusResult": _torus,
    "nlgrd.rotor.frequency_response.FrequencyResponse": _frequency_response,
    "nlgrd.rotor.frequency_response.StaticResult": _static,
    "nlgrd.rotor.modal.ModalResult": lambda: nlgrd.modes(nlgrd.load(TWO_SHAFT), n_modes=4),
    "nlgrd.rotor.modal.CampbellResult": lambda: nlgrd.campbell(
        nlgrd.load(TWO_SHAFT), rpm=[0.0, 3000.0], n_modes=4
    ),
    "nlgrd.timedomain.link_response.LinkTimeResponse": _link_time,
    "nlgrd.timedomain.run_down.RampResult": _ramp,
    "nlgrd.timedomain.sdof.TimeResponse": _sdof_time,
}


def _sdof_sweep():
    from nlgrd.nonlinear.tracing.sweep import sweep

    sd = _sdof()
    return sweep(sd.reduced_model(), sd.natural_frequency * np.array([0.7, 0.8]), 5, "up")


def test_every_result_class_has_a_small_case():
    """A new *Result/*Response class gets its case here (and so is held to the family)."""
    found = result_classes()
    assert len(found) >= 15
    assert sorted(set(found) - set(CASES)) == []


@pytest.mark.parametrize("name", sorted(CASES))
def test_every_result_has_to_frame_and_plot(name):
    """``to_frame()`` is a non-empty table whose columns are strings; ``plot(ax=ax)``
    draws on ``ax`` and returns it; ``plot()`` makes a new figure."""
    cls = result_classes().get(name)
    if cls is None:
        pytest.fail(f"{name} is gone: remove its case from CASES")
    res = CASES[name]()
    assert isinstance(res, cls)
    frame = res.to_frame()
    assert isinstance(frame, pd.DataFrame) and len(frame) > 0
    assert all(isinstance(c, str) for c in frame.columns)
    fig, ax = plt.subplots()
    assert res.plot(ax=ax) is ax
    assert ax.has_data()
    plt.close(fig)
    new = res.plot()
    assert new.figure is not fig
    plt.close(new.figure)


def test_static_result_of_a_matrix_model_plots_its_table():
    """A static deflection of a model of matrices (no rotor system) draws each DOF's value
    against its index, the numbers of its table (K q = f of the 2-DOF chain)."""
    from nlgrd.rotor.frequency_response import static_deflection

    res = static_deflection(_two_dof(), np.array([0.0, 10.0]))
    frame = res.to_frame()
    # K q = f by hand: q = K^-1 f = [10/4e5, 10/4e5 + 10/2e5] m
    np.testing.assert_allclose(frame["value [m or rad]"], [2.5e-5, 7.5e-5], rtol=1e-12)
    ax = res.plot()
    np.testing.assert_array_equal(ax.get_lines()[0].get_ydata(), frame["value [m or rad]"])
    plt.close(ax.figure)


def test_found_orbit_alone_has_to_frame_and_plot():
    orbit = _orbits()[0]
    assert orbit.to_frame().shape[0] == 1
    ax = orbit.plot()
    assert ax.has_data()
    plt.close(ax.figure)


# --- the new members, against independent numbers -----------------------------------------


def test_floquet_result_table_and_unit_circle():
    """The multipliers of the linear oscillator are exp(λ T) (closed form); the table
    holds them, largest modulus first, and the figure draws them with the unit circle
    (every point of it at |z| = 1 to rounding)."""
    res = _floquet()
    wn = np.sqrt(4e6)
    zeta = 20.0 / (2 * wn)
    lam = -zeta * wn + 1j * wn * np.sqrt(1 - zeta**2)
    exact = np.exp(lam * 2 * np.pi / OMEGA_FLOQUET)
    frame = res.to_frame()
    assert list(frame.columns) == ["multiplier_re [-]", "multiplier_im [-]", "multiplier_abs [-]"]
    mu = frame["multiplier_re [-]"].to_numpy() + 1j * frame["multiplier_im [-]"].to_numpy()
    # the Magnus product of a constant tangent: error ~1e-12 (measured 1e-15)
    np.testing.assert_allclose(np.sort_complex(mu), np.sort_complex([exact, exact.conjugate()]), atol=1e-9)
    np.testing.assert_allclose(frame["multiplier_abs [-]"], abs(exact), rtol=1e-9)
    ax = res.plot()
    circle = [ln for ln in ax.get_lines() if ln.get_gid() == "unit circle"]
    assert len(circle) == 1
    z = circle[0].get_xdata() + 1j * circle[0].get_ydata()
    np.testing.assert_allclose(np.abs(z), 1.0, rtol=1e-12)
    drawn = [ln for ln in ax.get_lines() if ln.get_gid() == "multipliers"]
    pts = np.concatenate([ln.get_xdata() + 1j * ln.get_ydata() for ln in drawn])
    np.testing.assert_allclose(np.sort_complex(pts), np.sort_complex(mu), rtol=1e-15)
    assert all(ln.get_markerfacecolor() != "none" for ln in drawn)  # inside: filled
    plt.close(ax.figure)


def test_torus_result_plot_marks_the_speed_without_a_torus():
    """Each torus an open square at its value in µm; the speed without one a cross on the
    bottom edge, counted in the legend."""
    res = _torus()
    frame = res.to_frame()
    ax = res.plot("dte_rms")
    squares = [ln for ln in ax.get_lines() if ln.get_label() == "quasi-periodic (torus HB)"]
    assert len(squares) == 1 and squares[0].get_markerfacecolor() == "none"
    np.testing.assert_array_equal(squares[0].get_ydata(), frame["mesh0.dte_rms [um]"].to_numpy()[[0, 2]])
    np.testing.assert_array_equal(squares[0].get_ydata(), res.outputs[[0, 2], 1] * 1e6)
    missing = [ln for ln in ax.get_lines() if ln.get_label() == "torus HB: no torus (1)"]
    assert len(missing) == 1 and list(missing[0].get_xdata()) == [2424.0]
    plt.close(ax.figure)
    with pytest.raises(ModelError, match="quantity"):
        res.plot("torque")


def test_orbit_search_table_and_figure():
    """One row per orbit with the orbit's own numbers (frequency in Hz, amplitude in µm,
    the Floquet verdict); the figure draws the stable orbits filled, the unstable open."""
    found = _orbits()
    frame = found.to_frame()
    assert len(frame) == len(found) == 3
    np.testing.assert_array_equal(frame["base_frequency [Hz]"], [o.omega / (2 * np.pi) for o in found])
    np.testing.assert_array_equal(frame["amplitude [um]"], [o.amplitude * 1e6 for o in found])
    assert frame["stable"].tolist() == [o.stable for o in found]
    np.testing.assert_array_equal(frame["mesh0.dte_rms [um]"], [o.metrics.dte_rms * 1e6 for o in found])
    assert str(frame["mesh0.back_contact"].dtype) == "boolean"
    assert frame["mesh0.back_contact"].tolist() == [bool(o.metrics.back_contact) for o in found]
    ax = found.plot()
    labels = sorted(ln.get_label() for ln in ax.get_lines())
    assert labels == ["period 1", "period 3", "period 3, unstable"]
    unstable = next(ln for ln in ax.get_lines() if ln.get_label() == "period 3, unstable")
    assert unstable.get_markerfacecolor() == "none"
    plt.close(ax.figure)


def test_link_continuation_table_never_calls_an_unstable_orbit_periodic():
    """The link path's continuation table (``LinkContinuationResult.to_frame``: the curve's
    table with the link columns) on the single-DOF pair's folded curve (tests/test_continuation.py:
    its middle branch unstable): every unstable row's ``response`` says "unstable periodic",
    every stable one "periodic"."""
    from nlgrd.nonlinear.results.link_results import LinkContinuationResult
    from nlgrd.nonlinear.tracing.continuation import continuation

    sd = _sdof()
    c = continuation(sd.reduced_model(), 1.2 * sd.natural_frequency, 0.6 * sd.natural_frequency, 5)
    assert c.turning_omegas.size == 2
    links = pd.DataFrame({"mesh.dte_rms [m]": c.curve.dte_rms})
    frame = LinkContinuationResult(c, links).to_frame()
    assert "mesh.dte_rms [um]" in frame and "base_frequency [Hz]" in frame  # written in µm
    np.testing.assert_array_equal(frame["mesh.dte_rms [um]"], c.curve.dte_rms * 1e6)
    unstable = frame["stable"].eq(False).to_numpy(bool)
    assert unstable.sum() >= 5
    assert set(frame.loc[unstable, "response"]) == {"unstable periodic"}
    assert set(frame.loc[~unstable, "response"]) == {"periodic"}

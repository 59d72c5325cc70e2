"""nlgrd.units: the one place of the written units' conversions and of the column names
``<quantity> [unit]`` / ``<link>.<quantity> [unit]`` (docs/conventions.md, "Column names")."""

from __future__ import annotations

import math

import numpy as np
import pytest

from nlgrd.errors import ModelError
from nlgrd.units import column, hz, omega_of_hz, parse_column, rpm, speed_of_rpm, um, written


def test_conversions_against_their_definitions():
    """1 rpm is 2π/60 rad/s, 1 Hz is 2π rad/s, 1 µm is 1e-6 m; each conversion and its
    inverse to rounding (1 ulp-scale, rtol 1e-15)."""
    assert rpm(2 * math.pi / 60) == pytest.approx(1.0, rel=1e-15)
    assert hz(2 * math.pi) == pytest.approx(1.0, rel=1e-15)
    assert um(1e-6) == pytest.approx(1.0, rel=1e-15)
    x = np.array([0.5, 1200.0, 31415.9])
    np.testing.assert_allclose(rpm(speed_of_rpm(x)), x, rtol=1e-15)
    np.testing.assert_allclose(hz(omega_of_hz(x)), x, rtol=1e-15)
    assert written(np.array([2e-6]), "m")[0] == "um"
    assert written(3.0, "N") == ("N", 3.0)
    with pytest.raises(ModelError, match="unit"):
        written(1.0, "kg")


def test_the_tables_expressions_are_kept_bit_for_bit():
    """The conversions are the expressions the tables used before (so CSVs are unchanged)."""
    rng = np.random.default_rng(1)
    w = rng.uniform(1.0, 1e5, 1000)
    assert np.array_equal(hz(w), w / (2 * np.pi))
    assert np.array_equal(rpm(w), w * 30 / math.pi)
    assert np.array_equal(um(w * 1e-9), w * 1e-9 * 1e6)


def test_column_names_and_their_parts():
    assert column("dte_rms", "um") == "dte_rms [um]"
    assert column("force_max", "N", link="mesh1") == "mesh1.force_max [N]"
    assert column("back_contact", None) == "back_contact"
    for name in ("dte_rms [um]", "mesh1.force_max [N]", "back_contact", "bearing_B.displacement_max [um]"):
        link, quantity, unit = parse_column(name)
        assert column(quantity, unit, link) == name
    for bad in ("", "dte rms", "a.b", "x[um]"):
        with pytest.raises(ModelError, match="quantity"):
            column(bad, "um")


def test_typed_output_columns():
    """An output's column follows the schema unless the table writes it otherwise (a
    one-mesh bearing's ``<bearing> <quantity> [unit]``); its factor to another unit of the
    same quantity is 1e6 from m to µm, and none between quantities."""
    from nlgrd.units import OutputColumn, factor

    c = OutputColumn("dte_rms", "m", "mesh0", "gear mesh")
    assert c.column == "mesh0.dte_rms [m]" and c.factor_to("um") == 1e6
    assert OutputColumn("force_max", "N", "B", "bearing", name="B force_max [N]").column == "B force_max [N]"
    assert factor("um", "m") == 1e-6 and factor("N", "N") == 1.0
    with pytest.raises(ModelError, match="unit"):
        factor("N", "um")

"""The single-DOF model of a gear pair with a varying mesh stiffness carries it.

``sdof_model`` dropped ``stiffness_variation`` (found in this session's review): the
single-DOF pair of a parametric FE model was silently the constant-k_h one. Reference:
the mesh law of the FE model itself (:func:`nlgrd.nonlinear.mesh_law.mesh_law`, whose
combination of k(θ) and e(θ) is checked against time integration in
tests/test_parametric_mesh.py and tests/test_parametric_mesh_fe.py); the single-DOF
model with that law is checked against its own time integration there too.
"""

import dataclasses
from pathlib import Path

import numpy as np
import pytest

from nlgrd.errors import ModelError
from nlgrd.gear.modifications import GearErrors
from nlgrd.io.model_file import load_model
from nlgrd.nonlinear.geared import sdof_model
from nlgrd.nonlinear.mesh_law import mesh_law

KUBO = Path(__file__).resolve().parents[1] / "data" / "case_studies" / "kubo.toml"


def _with(system, **changes):
    gp = dataclasses.replace(system.gear_pairs[0], **changes)
    return dataclasses.replace(system, gear_pairs=(gp,))


def test_sdof_model_keeps_the_varying_stiffness():
    system = load_model(KUBO)
    const = sdof_model(system)
    assert const.stiffness_variation.size == 1  # the paper's constant k_h
    par = _with(system, stiffness_variation=(1.0, 0.2, 0.0, 0.0, 0.05))
    sd = sdof_model(par)
    e, rho = mesh_law(par.gear_pairs[0], 30)
    np.testing.assert_array_equal(sd.stiffness_variation, rho)
    np.testing.assert_array_equal(sd.lste, e)
    assert sd.mass == const.mass and sd.mesh_stiffness == const.mesh_stiffness
    # the effective unloaded error differs from the LSTE by W_0/k_h (1 - 1/ρ): ~0.2 W_0/k_h
    shift = np.max(np.abs(sd.lste[1:3] - const.lste[1:3]))
    assert shift > 0.1 * par.gear_pairs[0].static_load / const.mesh_stiffness


def test_sdof_model_refuses_a_varying_stiffness_with_tooth_to_tooth_errors():
    system = load_model(KUBO)
    g = system.gear_pairs[0]
    spacing = np.zeros(g.geometry.teeth_gear)
    spacing[0] = 2e-6
    par = _with(system, stiffness_variation=(1.0, 0.2, 0.0), errors=GearErrors(spacing_gear=spacing))
    with pytest.raises(ModelError, match="mesh-periodic"):
        sdof_model(par)

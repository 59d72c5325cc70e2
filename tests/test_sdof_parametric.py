"""The single-DOF model of a gear pair with a varying mesh stiffness carries it.

``sdof_model`` dropped ``stiffness_variation``: the single-DOF pair of a parametric FE
model was silently the constant-k_h one. Reference: the combination of k(θ) and e(θ)
stated in :func:`nlgrd.nonlinear.laws.mesh_law.mesh_law` (Özgüven & Houser 1988), evaluated
here independently on 4096 samples: e_p(θ) = e(θ) + W_0/k_h (1 - 1/ρ(θ)) with e the
constant model's LSTE and ρ the given series, Fourier-analysed by FFT. 1/ρ of this ρ
(0.75 <= ρ <= 1.25) has harmonics decaying like 0.27^k, so 30 harmonics leave ~1e-17 of
W_0/k_h: the tolerance 1e-12 of it is rounding.
"""

import dataclasses
from pathlib import Path

import numpy as np
import pytest

from nlgrd.errors import ModelError
from nlgrd.gear.modifications import GearErrors
from nlgrd.io.model_file import load_model
from nlgrd.nonlinear.fourier.harmonics import analyse, evaluate
from nlgrd.nonlinear.models.sdof import sdof_model

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
    assert sd.mass == const.mass and sd.mesh_stiffness == const.mesh_stiffness
    theta = 2 * np.pi * np.arange(4096) / 4096
    rho = 1 + 0.2 * np.cos(theta) + 0.05 * np.sin(2 * theta)
    np.testing.assert_allclose(evaluate(sd.stiffness_variation, theta), rho, rtol=0, atol=1e-14)
    scale = par.gear_pairs[0].static_load / const.mesh_stiffness
    e_p = evaluate(const.lste, theta) + scale * (1 - 1 / rho)
    ref = analyse(e_p, (sd.lste.size - 1) // 2)
    assert np.max(np.abs(sd.lste - ref)) <= 1e-12 * scale
    assert np.max(np.abs(sd.lste - const.lste)) > 0.1 * scale  # not the constant model's


def test_sdof_model_refuses_a_varying_stiffness_with_tooth_to_tooth_errors():
    system = load_model(KUBO)
    g = system.gear_pairs[0]
    spacing = np.zeros(g.geometry.teeth_gear)
    spacing[0] = 2e-6
    par = _with(system, stiffness_variation=(1.0, 0.2, 0.0), errors=GearErrors(spacing_gear=spacing))
    with pytest.raises(ModelError, match="mesh-periodic"):
        sdof_model(par)

"""The shipped rotors with a bearing clearance (issue 33 item 9): data/models/rub_rotor.toml
(an unbalanced disk in a rub ring, no gear mesh) and data/models/two_shaft_clearance.toml
(the two-shaft gear drive with a journal in a Hertzian clearance)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
import scipy.sparse.linalg as spla

from nlgrd.cli import main
from nlgrd.io.model_file import load_model
from nlgrd.rotor.assembly import assemble

ROOT = Path(__file__).resolve().parent.parent
RUB = ROOT / "data" / "models" / "rub_rotor.toml"
GEARED = ROOT / "data" / "models" / "two_shaft_clearance.toml"


def test_rub_rotor_sweeps_with_the_default_quantity_and_matches_the_linear_rotor_off_contact(
    tmp_path, capsys
):
    """`nlgrd sweep` of a clearance model without a gear pair runs with every default (the
    default quantity was a mesh's DSLR: "no link 'dslr'") and plots the rub's largest
    force. Where the disk stays inside its 0.2 mm ring (2000-3000 rpm) the response is the
    linear rotor's: the disk's whirl orbit radius equals the largest modulus over the
    period of the linear unbalance response, solved here directly from the assembled
    matrices (K + i Ω C(Ω) - Ω² M) q = F at the shaft speed Ω, independent of the link
    reduction. 1e-5 relative: the orbit's largest radius is taken from samples, 1024 here
    and the link's own elsewhere, each within (π/N)²/2 < 5e-6 of the largest radius of
    the smooth elliptic orbit; the two solves agree to rounding."""
    out = tmp_path / "rub.csv"
    argv = ["sweep", str(RUB), "--rpm", "2000:3000:3", "--direction", "up", "--harmonics", "5"]
    assert main([*argv, "--out", str(out)]) == 0
    text = capsys.readouterr().out
    assert "links rub" in text and "base frequency = shaft" in text
    df = pd.read_csv(out)
    assert (df["rub.contact_fraction [-]"] == 0).all() and (df["rub.force_max [N]"] == 0).all()
    system = load_model(RUB)
    lin = assemble(system, mesh_stiffness=False, mesh_damping=False)
    u = system.unbalance[0]
    dofs = system.dofs.node_dofs(u.shaft, u.node)
    for rpm, radius in zip(df["shaft_speed [rpm]"], df["rub.displacement_max [um]"] * 1e-6, strict=True):
        speed = rpm * np.pi / 30
        F = np.zeros(lin.n_dofs, dtype=complex)
        amp = u.amount * speed**2 * np.exp(1j * u.phase)
        F[dofs[1]], F[dofs[2]] = amp, -1j * amp
        Z = (lin.stiffness(speed) + 1j * speed * lin.damping(speed) - speed**2 * lin.M).tocsc()
        q = spla.spsolve(Z, F)
        theta = np.linspace(0, 2 * np.pi, 1024, endpoint=False)
        y = np.real(q[dofs[1]] * np.exp(1j * theta))
        z = np.real(q[dofs[2]] * np.exp(1j * theta))
        np.testing.assert_allclose(radius, np.max(np.hypot(y, z)), rtol=1e-5)
    assert out.with_suffix(".png").stat().st_size > 0


def test_two_shaft_clearance_model_runs_on_its_clearance(tmp_path, capsys):
    """The geared clearance model: links B1 and mesh0; the mesh load pushes the pinion's
    free-end journal onto its 20 µm clearance (contact all period, radial displacement
    beyond 20 µm) at every stable point."""
    out = tmp_path / "cl.csv"
    argv = ["sweep", str(GEARED), "--rpm", "2000:3000:3", "--direction", "up", "--harmonics", "9"]
    assert main([*argv, "--out", str(out)]) == 0
    assert "links B1, mesh0" in capsys.readouterr().out
    df = pd.read_csv(out)
    ok = df["stable"].eq(True)
    assert ok.any()
    assert (df.loc[ok, "B1.contact_fraction [-]"] == 1).all()
    assert (df.loc[ok, "B1.displacement_max [um]"] > 20.0).all()

"""``nlgrd sweep --search-at`` on a link model (issue 33 item 7): the rub rotor
(data/models/rub_rotor.toml, an unbalanced disk in a 0.2 mm rub ring with linear contact
5e7 N/m) has at 6000 rpm both the free whirl the sweep follows and a stable rubbing orbit
no sweep from below reaches; the search finds both, flags the first as the sweep's, and
follows the second over the grid."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from nlgrd.cli import main

RUB = Path(__file__).resolve().parent.parent / "data" / "models" / "rub_rotor.toml"
CLEARANCE, STIFFNESS = 2.0e-4, 5.0e7  # the model file's rub ring [m], [N/m]


def test_link_search_finds_and_follows_the_rubbing_orbit(tmp_path, capsys):
    """Every contact row obeys the ring's law: the largest force is k (r_max - c) for the
    linear contact (force monotone in the radial displacement, both maxima over the same
    samples: 1e-9 relative, rounding); the free orbit has no force and stays inside c.
    The stable rubbing orbit is not the sweep's and is followed over the whole grid, each
    followed point on the same law."""
    out = tmp_path / "rub.csv"
    argv = ["sweep", str(RUB), "--rpm", "5000:7000:5", "--harmonics", "5", "--direction", "up"]
    assert main([*argv, "--search-at", "6000", "--search-periods", "1", "--out", str(out)]) == 0
    text = capsys.readouterr().out
    assert "(the sweep's)" in text and "followed: period 1" in text
    orbits = pd.read_csv(tmp_path / "rub_orbits.csv")
    branches = pd.read_csv(tmp_path / "rub_branches.csv")
    force, radius = orbits["rub.force_max [N]"], orbits["rub.displacement_max [um]"] * 1e-6
    free = orbits["on the sweep"].astype(bool)
    assert free.sum() == 1 and force[free].iloc[0] == 0 and radius[free].iloc[0] < CLEARANCE
    rubbing = ~free & orbits["stable"].astype(bool)
    assert rubbing.sum() >= 1
    touching = force > 0
    np.testing.assert_allclose(force[touching], STIFFNESS * (radius[touching] - CLEARANCE), rtol=1e-9)
    ok = branches["stable"].astype(bool)
    # the speeds as typed (issue 36 item 3), not their round trip through rad/s
    assert ok.any() and set(branches.loc[ok, "shaft_speed [rpm]"]) == {5000, 5500, 6000, 6500, 7000}
    sweep = pd.read_csv(out)
    assert list(sweep["shaft_speed [rpm]"]) == [5000, 5500, 6000, 6500, 7000]
    b_force = branches.loc[ok, "rub.force_max [N]"]
    b_radius = branches.loc[ok, "rub.displacement_max [um]"] * 1e-6
    assert (b_force > 0).all()
    np.testing.assert_allclose(b_force, STIFFNESS * (b_radius - CLEARANCE), rtol=1e-9)

"""Loads a rotor model carries besides its parts: mass unbalances of its disks."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from nlgrd.errors import ModelError, check_positive, check_real


@dataclass(frozen=True)
class Unbalance:
    """A mass unbalance m e at a node, rotating with its shaft (forward, y towards z).

    In a model file: a ``[[unbalance]]`` entry. It excites its node at |s| Ω (s the shaft's
    speed ratio, Ω the reference speed) with the force m e (s Ω)²; only the link analyses
    (:mod:`nlgrd.nonlinear.models.link_model`) model it.

    Parameters
    ----------
    shaft, node : int
        Where it sits.
    amount : float
        m e [kg m], >= 0.
    phase : float
        Angle of the unbalance at t = 0 from the y axis [rad].
    """

    shaft: int
    node: int
    amount: float
    phase: float = 0.0

    def __post_init__(self):
        for key in ("shaft", "node"):
            v = getattr(self, key)
            if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or v < 0:
                raise ModelError(key, f"must be a non-negative integer, got {v!r}")
        check_positive("amount", self.amount, allow_zero=True)
        check_real("phase", self.phase)

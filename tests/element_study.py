"""Mesh convergence of the shaft element's two mass matrices (issue 10, item 5).

Run from the repository root (about 15 s)::

    .venv/bin/python tests/element_study.py

prints the table of docs/verification.md ("Shaft element: mesh convergence of the mass
matrix"); ``tests/test_element_convergence.py`` imports these functions and asserts the
orders and the comparison.

Method. :class:`nlgrd.rotor.shaft.ShaftElement` accepts two mass matrices, ``"consistent"`` (the
default, chosen by this study) and ``"blended"``; no other formulation exists (``shear`` and
``rotary_inertia`` change the beam theory, not its discretisation). For each case every
original shaft element is split into f = 1, 2, 4, 8, 16 equal elements, the nodes of
disks, bearings, couplings and gear pairs mapped n -> f n as
``benchmarks/bench_nonlinear.py`` ``refine`` does, and the undamped natural frequencies
come from :func:`nlgrd.rotor.modal.modal_analysis` (``damped=False``). Each mode's observed
order is p = log2((ω_4 - ω_8) / (ω_8 - ω_16)) and its reference the Richardson
extrapolation ω_16 + (ω_16 - ω_8) / (2^p - 1) from the two finest meshes, separately for
each formulation; both tend to the same limit, and the two references agree to within a
fraction of the f = 16 error (:func:`reference_spread`), so the columns f = 1-8 do not
depend on which one is used. A group's error is the largest relative error of its modes;
its order is log2 of the ratio of the largest relative changes from f = 4 to 8 and from
f = 8 to 16 (the modes that set the group's error set its order); the range of its
resolved modes' orders (:data:`RESOLVED`) follows in brackets.

Modes are matched by their rank in frequency. For the single-shaft cases (a)-(c) these
are the distinct lateral modes (one of each y-z pair); for the model files, all flexible
modes, lateral, torsional, axial and coupled. Mode ranks stay matched between meshes:
a mode changing rank would show as an undefined or wild order, and every order is
finite, every group order near 2 or 4.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from nlgrd import Bearing, Disk, Material, RotorSystem, Shaft
from nlgrd.io.model_file import load_model
from nlgrd.rotor.modal import modal_analysis
from nlgrd.rotor.system import refined

ROOT = Path(__file__).resolve().parents[1]
STEEL = Material("steel", density=7850.0, young_modulus=2.1e11, poisson_ratio=0.3)
FORMULATIONS = ("blended", "consistent")
FACTORS = (1, 2, 4, 8, 16)
#: A mode's observed order is resolved when its frequency changes by at least this much
#: (relative) from f = 8 to 16: 70 x the eigensolvers' disagreement (at most 1.4e-9,
#: sparse against dense on two_shaft.toml at f = 16; 1e-11 to 6e-10 on the other meshes
#: of (a)-(d)), so its order is known to about 0.04. Below it (a few low modes, already
#: converged to 1e-8) the order is noise and left out of the per-mode ranges.
RESOLVED = 1e-7


def refine(system: RotorSystem, factor: int, mass_matrix: str | None = None) -> RotorSystem:
    """``system`` with every shaft element split into ``factor`` equal elements
    (:func:`nlgrd.rotor.system.refined`); ``mass_matrix`` sets every element's formulation."""
    out = refined(system, factor)
    if mass_matrix is None:
        return out
    rep = dataclasses.replace
    shafts = tuple(
        rep(s, elements=tuple(rep(e, mass_matrix=mass_matrix) for e in s.elements)) for s in out.shafts
    )
    return rep(out, shafts=shafts)


# --------------------------------------------------------------------------------------
# Cases
# --------------------------------------------------------------------------------------

#: The single-shaft cases use the main section of data/models/two_shaft.toml: 45 mm
#: diameter in 50 mm elements (L/D = 1.1, Phi = 1.78), 0.5 m long, 10 elements.
LENGTH, DIAMETER, N_ELEMENTS = 0.5, 0.045, 10


def _shaft() -> Shaft:
    return Shaft.uniform(LENGTH, DIAMETER, N_ELEMENTS, STEEL)


def _pins() -> tuple[Bearing, ...]:
    """Pins at both ends: springs of 1e9 EI/L^3 (as in tests/test_linear_rotor.py)."""
    k = 1e9 * STEEL.young_modulus * np.pi * DIAMETER**4 / 64 / LENGTH**3
    return (Bearing(0, 0, kyy=k, kzz=k), Bearing(0, N_ELEMENTS, kyy=k, kzz=k))


def _disks() -> tuple[Disk, ...]:
    """The gear blank of two_shaft.toml at node 3 (x = 0.15 m), its motor at node 7 (0.35 m)."""
    return (
        Disk(0, 3, mass=0.9248, diametral_inertia=5.953e-4, polar_inertia=1.156e-3, name="gear blank"),
        Disk(0, 7, mass=5.057, diametral_inertia=6.295e-3, polar_inertia=5.762e-3, name="motor"),
    )


def _elastic() -> tuple[Bearing, ...]:
    """The rolling-element bearings of two_shaft.toml (1.5e8 N/m) at nodes 1 and 9:
    50 mm overhangs at both ends, as on the shipped models."""
    return (Bearing(0, 1, kyy=1.5e8, kzz=1.5e8), Bearing(0, N_ELEMENTS - 1, kyy=1.5e8, kzz=1.5e8))


@dataclass(frozen=True)
class Case:
    """A model to refine, how many modes to compare and how to group them."""

    name: str
    system: RotorSystem
    n_modes: int
    lateral_only: bool  # distinct lateral modes only (one of each degenerate y-z pair)
    groups: tuple[tuple[int, int], ...]  # 1-based inclusive ranges of mode ranks
    shipped: bool = False  # a model file of data/: its element count is the users'


#: Model files of data/ in the study. data/case_studies/kubo.toml is left out: its shafts
#: carry 1/1000 of steel's density (the gear inertias include them), so the shaft mass
#: matrix hardly enters and several of its modes do not move with the mesh at all.
MODEL_FILES = (
    ("(d)", "data/models/two_shaft.toml", 30),
    ("(e)", "data/models/single_shaft.toml", 20),
    ("(f)", "data/case_studies/kahraman_blankenship.toml", 20),
)


def cases() -> list[Case]:
    """(a) bare shaft, pinned-pinned; (b) with two disks; (c) bare on elastic bearings
    with overhangs; (d)-(f) the model files (two_shaft.toml is the geared two-shaft
    example)."""
    lateral = ((1, 2), (3, 5), (6, 8))
    out = [
        Case("(a) bare, pinned-pinned", RotorSystem((_shaft(),), bearings=_pins()), 8, True, lateral),
        Case(
            "(b) 2 disks, pinned-pinned",
            RotorSystem((_shaft(),), disks=_disks(), bearings=_pins()),
            8,
            True,
            lateral,
        ),
        Case("(c) bare, elastic bearings", RotorSystem((_shaft(),), bearings=_elastic()), 8, True, lateral),
    ]
    for label, path, n in MODEL_FILES:
        groups = tuple((a, min(a + 9, n)) for a in range(1, n + 1, 10))
        out.append(Case(f"{label} {Path(path).name}", load_model(ROOT / path), n, False, groups, True))
    return out


# --------------------------------------------------------------------------------------
# Study
# --------------------------------------------------------------------------------------


def frequencies(case: Case, factor: int, mass_matrix: str) -> np.ndarray:
    """Natural frequencies [Hz] of ``case`` refined by ``factor``, ``case.n_modes`` of them."""
    system = refine(case.system, factor, mass_matrix)
    if not case.lateral_only:
        f = modal_analysis(system, n_modes=case.n_modes, damped=False).natural_frequencies
    else:
        res = modal_analysis(system, n_modes=4 * case.n_modes + 10, damped=False)
        f = res.natural_frequencies[np.array(res.kinds) == "lateral"][::2][: case.n_modes]
    if len(f) != case.n_modes:
        raise RuntimeError(f"{case.name}, f = {factor}: {len(f)} modes, wanted {case.n_modes}")
    return f


@dataclass
class Result:
    """Frequencies of one case and formulation on every mesh, with the reference."""

    case: Case
    mass_matrix: str
    freqs: np.ndarray  # (len(FACTORS), n_modes) [Hz]

    @property
    def order(self) -> np.ndarray:
        """Observed order of each mode, from f = 4, 8, 16."""
        w4, w8, w16 = self.freqs[-3:]
        return np.log2((w4 - w8) / (w8 - w16))

    @property
    def reference(self) -> np.ndarray:
        """Richardson extrapolation from f = 8 and 16 with the observed order [Hz]."""
        w8, w16 = self.freqs[-2:]
        return w16 + (w16 - w8) / (2.0**self.order - 1)

    @property
    def signed_errors(self) -> np.ndarray:
        """f / f_ref - 1, (len(FACTORS), n_modes)."""
        return self.freqs / self.reference - 1

    @property
    def errors(self) -> np.ndarray:
        return np.abs(self.signed_errors)

    def group_error(self, group: tuple[int, int]) -> np.ndarray:
        """Largest relative error of the group's modes on each mesh, (len(FACTORS),)."""
        a, b = group
        return self.errors[:, a - 1 : b].max(axis=1)

    def group_order(self, group: tuple[int, int]) -> float:
        """Observed order of a group of modes, from f = 4, 8, 16 (:func:`group_order`)."""
        return group_order(self.freqs[-3:], group)

    @property
    def resolved(self) -> np.ndarray:
        """Modes whose observed order is resolved (see :data:`RESOLVED`)."""
        w8, w16 = self.freqs[-2:]
        return np.abs(w8 - w16) / w16 >= RESOLVED

    def mode_orders(self, group: tuple[int, int]) -> np.ndarray:
        """Observed orders of the group's resolved modes."""
        a, b = group
        return self.order[a - 1 : b][self.resolved[a - 1 : b]]


def group_order(freqs: np.ndarray, group: tuple[int, int]) -> float:
    """log2 of the ratio of the group's largest changes relative to the finest mesh,
    from the first to the second and from the second to the third row of ``freqs``
    (three meshes, each twice as fine as the one before); for a single mode, its order."""
    a, b = group
    w1, w2, w3 = freqs[:, a - 1 : b]
    return float(np.log2(np.max(np.abs(w1 - w2) / w3) / np.max(np.abs(w2 - w3) / w3)))


def study(case: Case, mass_matrix: str, factors: tuple[int, ...] = FACTORS) -> Result:
    return Result(case, mass_matrix, np.array([frequencies(case, f, mass_matrix) for f in factors]))


def reference_spread(results: dict[str, Result]) -> np.ndarray:
    """|difference of the two formulations' references| / the larger f = 16 error, per mode."""
    b, c = results["blended"], results["consistent"]
    spread = np.abs(b.reference / c.reference - 1)
    return spread / np.maximum(b.errors[-1], c.errors[-1])


def run() -> list[dict[str, Result]]:
    """Every case with both formulations: [{formulation: Result}] in the order of cases()."""
    return [{m: study(c, m) for m in FORMULATIONS} for c in cases()]


def table(runs: list[dict[str, Result]]) -> str:
    """The Markdown table of docs/verification.md."""
    head = " | ".join(f"f = {f}" for f in FACTORS)
    lines = [
        f"| case | modes | formulation | {head} | observed order (per mode) |",
        "|---|---|---|" + "---|" * len(FACTORS) + "---|",
    ]
    for res in runs:
        for g in next(iter(res.values())).case.groups:
            for m, r in res.items():
                a, b = g
                fr = r.reference[a - 1 : b]
                cells = " | ".join(f"{x:.1e}" for x in r.group_error(g))
                o = r.mode_orders(g)
                lines.append(
                    f"| {r.case.name} | {a}-{b} ({fr.min():.0f}-{fr.max():.0f} Hz) | {m} | {cells} | "
                    f"{r.group_order(g):.2f} ({o.min():.2f}-{o.max():.2f}) |"
                )
    return "\n".join(lines)


def main() -> None:
    runs = run()
    print(table(runs))
    print()
    print("largest |reference difference| / f = 16 error, per case:")
    for res in runs:
        print(f"  {res['blended'].case.name}: {reference_spread(res).max():.2f}")
    print(f"modes whose order is not resolved (change f = 8 -> 16 below {RESOLVED:g}):")
    for res in runs:
        for m, r in res.items():
            if not r.resolved.all():
                idx = np.flatnonzero(~r.resolved) + 1
                print(f"  {r.case.name}, {m}: modes {', '.join(map(str, idx))}")


if __name__ == "__main__":
    main()

"""The tables of link-model analyses: every link's outputs ``<link>.<quantity>`` per point
of a sweep (:class:`LinkSweepResult`) or a continuation curve (:class:`LinkContinuationResult`),
beside the points' own columns.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import pandas as pd
from numpy.typing import NDArray

from nlgrd.errors import ModelError
from nlgrd.nonlinear.fourier.harmonics import real_to_complex
from nlgrd.nonlinear.results.bearing_loads import (
    BEARING_OUTPUTS,
    bearing_names,
    link_bearing_outputs_of_points,
)
from nlgrd.nonlinear.results.sweep_results import ContinuationResult, SweepResult
from nlgrd.units import OutputColumn, floor_rounding, parse_column, rpm, written_frame, written_name

__all__ = [
    "LinkContinuationResult",
    "LinkSweepResult",
    "NOT_JUMP_QUANTITIES",
    "POINT_RENAMES",
    "bearing_columns",
    "link_column",
    "link_rows",
    "mesh_amplitudes",
    "metric_names",
    "output_columns",
    "output_names",
    "point_outputs",
    "points_outputs",
    "with_amplitudes",
    "with_links",
    "with_speed",
]


def with_links(frame: pd.DataFrame, links: pd.DataFrame) -> pd.DataFrame:
    """A sweep's or curve's table with the link columns in place of the first mesh's
    metrics, its frequency column named ``base_frequency [Hz]``: the links' columns in
    their written units (:func:`nlgrd.units.written_frame`: lengths in µm) with rounding
    written as 0 (:func:`nlgrd.units.floor_rounding`).

    Parameters
    ----------
    frame : pandas.DataFrame
        :meth:`SweepResult.to_frame` of the points.
    links : pandas.DataFrame
        One row per point: ``<link>.<quantity> [SI unit]`` columns.

    Returns
    -------
    pandas.DataFrame
    """
    drop = [c for c in frame.columns if c.startswith(("dte_", "force_", "dslr", "contact_loss", "back_"))]
    frame = frame.drop(columns=drop).rename(columns=POINT_RENAMES)
    return pd.concat([frame, floor_rounding(written_frame(links))], axis=1)


#: The point columns of :meth:`SweepResult.to_frame` a link table renames
#: (docs/conventions.md, "Column names").
POINT_RENAMES = {"subharmonic_amp [um]": "subharmonic_amplitude [um]"}


def with_speed(frame: pd.DataFrame, omega: NDArray, speed_per_base: float | None, unit: str = "Hz"):
    """``frame`` with the reference shaft's speed ``shaft_speed [rpm]`` when
    ``speed_per_base`` is known: first when the speeds were given in rpm, else after
    ``base_frequency [Hz]``.

    Parameters
    ----------
    frame : pandas.DataFrame
        A link table (``base_frequency [Hz]`` first).
    omega : ndarray
        The base frequency of each row [rad/s].
    speed_per_base : float or None
        Reference shaft speed per base frequency [-]; None: no speed column.
    unit : {"Hz", "rpm"}
        How the speeds were given.

    Returns
    -------
    pandas.DataFrame
    """
    if speed_per_base is not None and "shaft_speed [rpm]" not in frame:
        values = rpm(np.asarray(omega, dtype=float) * speed_per_base)
        frame = frame.copy()  # one block: the tables joined column by column are fragmented
        frame.insert(0 if unit == "rpm" else 1, "shaft_speed [rpm]", values)
    return frame


#: A mesh's outputs that the default jumps do not ask: the mean DTE, its peak-to-peak and
#: the smallest mesh force, written since issue 33 item 5 for the one-mesh table; the jumps
#: stay those of the RMS, the largest force, the DSLR and the contact (a mean or a smallest
#: force that moves by a tenth is no jump of the response level).
NOT_JUMP_QUANTITIES = ("dte_mean", "dte_p2p", "force_min")


def _jumps_on(column: str) -> bool:
    """Whether the default jumps ask ``column`` (not one of :data:`NOT_JUMP_QUANTITIES`,
    not a harmonic amplitude ``dte_amp_<k>``)."""
    quantity = parse_column(column)[1]
    return quantity not in NOT_JUMP_QUANTITIES and not quantity.startswith("dte_amp_")


def link_column(links: pd.DataFrame, quantity: str | None, bearings: Sequence[str] = ()) -> str:
    """The column ``<link>.<quantity> [unit]`` of ``links`` that ``quantity`` names, as
    ``nlgrd sweep --quantity`` reads it: ``LINK.QUANTITY``, or a bare quantity of the first
    link that has it (meshes first, the linear bearings last); None: a mesh's DSLR, else the
    first link's largest force.

    Parameters
    ----------
    links : pandas.DataFrame
        The links' (and linear bearings') outputs, ``<name>.<quantity> [unit]`` columns.
    quantity : str or None
        The quantity asked for.
    bearings : sequence of str
        Which columns are the linear bearings'.

    Returns
    -------
    str

    Raises
    ------
    ModelError
        (``quantity``) No column of that name.
    """

    def split(column: str) -> tuple[str, str]:
        name, _, q = column.partition(".")
        return name, q.split(" [")[0]

    own = [c for c in links.columns if c not in bearings]
    meshes = [split(c)[0] for c in own if split(c)[1] == "dslr"]
    if quantity is None:
        quantity = "dslr" if meshes or not own else f"{split(own[0])[0]}.force_max"
    name, _, q = quantity.rpartition(".")
    order = list(dict.fromkeys(meshes + [split(c)[0] for c in own] + [split(c)[0] for c in links.columns]))
    for n in [name] if name else order:
        match = [c for c in links.columns if split(c) == (n, q)]
        if match:
            return match[0]
    names = ", ".join(c.split(" [")[0] for c in links.columns)
    raise ModelError("quantity", f"no output {quantity!r}; the columns are {names}")


@dataclass(frozen=True)
class LinkSweepResult:
    """A sweep of a link model: the harmonic-balance points and every link's outputs.

    Attributes
    ----------
    result : SweepResult
        The points (harmonics of all link coordinates, convergence, stability).
    links : pandas.DataFrame
        One row per point: ``<link>.<quantity>`` columns, over the point's whole period
        (2T for a period-2 point), then every linear bearing's ``<bearing>.<quantity>``;
        NaN where the point did not converge or has no stable periodic response.
    bearings : tuple of str
        Which of those columns are the linear bearings' (recovered, not a link's own).
    speed_per_base : float or None
        Reference shaft speed per base frequency: the table has ``shaft_speed [rpm]``
        (:func:`with_speed`); None: not known, no speed column.
    speed_unit : {"Hz", "rpm"}
        How the speeds were given: "rpm" puts the shaft speed first.
    coexisting : tuple of CoexistingBranch or None
        The coexisting branches searched beside the sweep's jumps
        (:mod:`nlgrd.nonlinear.results.coexisting_results`); None: not searched.
    coexisting_note : str
        One line on how they were checked where the model has no exact flow ("" else).

    :attr:`links` holds the outputs in SI units as the engine computed them; the table
    (:meth:`to_frame`) writes them in the units of docs/conventions.md ("Column names").
    """

    result: SweepResult
    links: pd.DataFrame
    bearings: tuple = ()
    speed_per_base: float | None = None
    speed_unit: str = "Hz"
    coexisting: tuple | None = None
    coexisting_note: str = ""

    def to_frame(self) -> pd.DataFrame:
        """The sweep's table: ``base_frequency [Hz]`` (a one-mesh model's mesh frequency)
        and ``shaft_speed [rpm]`` (:func:`with_speed`), the points' columns
        and every link's and linear bearing's ``<name>.<quantity> [unit]`` in written units.
        With :attr:`coexisting` searched, a ``branch`` column: "sweep" on the sweep's rows,
        then the rows of each coexisting branch ("coexisting k", stable and unstable rows
        with their outputs; :func:`~nlgrd.nonlinear.results.coexisting_results.with_branches`).

        Returns
        -------
        pandas.DataFrame
        """
        frame = with_links(self.result.to_frame(), self._answered_amplitudes())
        frame = with_speed(frame, self.result.omega, self.speed_per_base, self.speed_unit)
        if self.coexisting is None:
            return frame
        from nlgrd.nonlinear.results.coexisting_results import with_branches

        parts = [
            with_speed(
                with_links(_all_rows(b.result).to_frame(), b.links),
                b.result.omega,
                self.speed_per_base,
                self.speed_unit,
            )
            for b in self.coexisting
        ]
        return with_branches(frame, parts, [b.name for b in self.coexisting])

    def bifurcations(self) -> pd.DataFrame:
        """The bifurcations reported on the coexisting branches, each ``confirmed`` on the
        exact flow or not (:func:`~nlgrd.nonlinear.results.coexisting_results.bifurcation_frame`;
        empty when none was searched).

        Returns
        -------
        pandas.DataFrame
        """
        from nlgrd.nonlinear.results.coexisting_results import bifurcation_frame

        return bifurcation_frame(self.coexisting or (), self.speed_per_base)

    def _answered_amplitudes(self) -> pd.DataFrame:
        """:attr:`links` with the first mesh's ``dte_amp_<k>`` of the points a time
        integration or a torus answered: the mesh result's amplitudes (a torus's: of its
        mesh-synchronous part), as the one-mesh table wrote them."""
        timed = np.asarray(self.result.time_answered, dtype=bool)
        amps = [c for c in self.links.columns if parse_column(c)[1].startswith("dte_amp_")]
        if not (timed.any() and amps):
            return self.links
        first = parse_column(amps[0])[0]
        links = self.links.copy()
        A = np.asarray(self.result.amplitudes, dtype=float)
        for k in range(A.shape[1]):
            name = f"{first}.dte_amp_{k} [m]"
            if name in links.columns:
                links.loc[timed, name] = A[timed, k]
        return links

    def jumps(self, quantities: str | Sequence[str] | None = None, rtol: float = 0.1, ratio: float = 3.0):
        """Jumps of each sweep direction in the links' outputs (:meth:`SweepResult.jumps`
        on the columns of :attr:`links`).

        Parameters
        ----------
        quantities : str or sequence of str, optional
            ``<link>.<quantity>`` columns; default every link's but
            :data:`NOT_JUMP_QUANTITIES` (the linear bearings follow them: a bearing whose
            force changes smoothly by a third is no jump).
        rtol, ratio : float
            As :func:`nlgrd.nonlinear.results.jumps.find_jumps` [-].

        Returns
        -------
        list of Jump
        """
        if quantities is None:
            quantities = [c for c in self.links.columns if c not in self.bearings and _jumps_on(c)]
        qs = [quantities] if isinstance(quantities, str) else list(quantities)
        for q in qs:
            if q not in self.links.columns:
                raise ModelError(
                    "quantities", f"no link output {q!r}; the columns are {list(self.links.columns)}"
                )
        return self.result.jumps_of({q: self.links[q].to_numpy() for q in qs}, rtol, ratio)

    def plot(self, quantity: str | None = None, ax=None):
        """One link's (or linear bearing's) output against the base frequency, drawn as the
        command line draws it (:func:`nlgrd.plotting.sweep_figures.plot_link_sweep`: stable
        filled, unstable open, points without a response marked, the jumps of
        :meth:`jumps` as dotted arrows).

        Parameters
        ----------
        quantity : str, optional
            ``LINK.QUANTITY`` or a bare quantity (:func:`link_column`); default a mesh's
            DSLR, else the first link's largest force.
        ax : matplotlib.axes.Axes, optional
            Axes to draw on; a new figure when None.

        Returns
        -------
        matplotlib.axes.Axes
        """
        from nlgrd.plotting.nonlinear import jump_table
        from nlgrd.plotting.sweep_figures import plot_link_sweep

        column = written_name(link_column(self.links, quantity, self.bearings))
        jumps = jump_table(self.jumps())  # the jumps the command line lists
        return plot_link_sweep(self.to_frame(), "base_frequency [Hz]", column, None, ax=ax, jumps=jumps)


def _all_rows(branch: SweepResult) -> SweepResult:
    """A coexisting branch whose table keeps the outputs of its unstable rows too (a branch
    is drawn stable and unstable; its ``stable`` column tells which)."""
    from dataclasses import replace

    return replace(branch, no_stable=np.zeros(len(branch), dtype=bool))


def metric_names(link) -> list[str]:
    """The names (with units) of a link's per-point outputs, in its ``metrics`` order.

    Parameters
    ----------
    link : NonlinearLink
        The link.

    Returns
    -------
    list of str
    """
    return list(link.metrics(np.zeros((link.n_coords, 3)), 1.0))


def output_names(model) -> list[str]:
    """The ``<name>.<quantity> [unit]`` columns of a link model's points: every link's,
    then every linear bearing's (:data:`BEARING_OUTPUTS`).

    Parameters
    ----------
    model : nlgrd.nonlinear.models.link_model.LinkModel
        The model.

    Returns
    -------
    list of str
    """
    return [c.column for c in output_columns(model)]


def output_columns(model) -> list[OutputColumn]:
    """The typed description of a link model's output columns: per column its quantity,
    unit, owner and the owner's kind (the link's ``kind``, "bearing" for a linear bearing);
    every link's columns first, then every linear bearing's.

    Parameters
    ----------
    model : nlgrd.nonlinear.models.link_model.LinkModel
        The model.

    Returns
    -------
    list of nlgrd.units.OutputColumn
        In the table's order (:func:`output_names`).
    """
    out = []
    for lk in model.links:
        for name in metric_names(lk):
            _, quantity, unit = parse_column(name)
            out.append(OutputColumn(quantity, unit, lk.name, getattr(lk, "kind", "link")))
    for name in bearing_columns(model):
        owner, quantity, unit = parse_column(name)
        out.append(OutputColumn(quantity, unit, owner, "bearing"))
    return out


def bearing_columns(model) -> tuple[str, ...]:
    """The linear bearings' columns among :func:`output_names`.

    Parameters
    ----------
    model : nlgrd.nonlinear.models.link_model.LinkModel
        The model.

    Returns
    -------
    tuple of str
    """
    return tuple(f"{b}.{q}" for b in bearing_names(model.system) for q in BEARING_OUTPUTS)


def point_outputs(model, harmonics: NDArray, omega: float) -> dict[str, float]:
    """Every link's outputs (its ``metrics``) and every linear bearing's (force and
    displacement recovered from the link coordinates:
    :func:`~nlgrd.nonlinear.results.bearing_loads.link_bearing_outputs`) at one solved point.

    Parameters
    ----------
    model : nlgrd.nonlinear.models.link_model.LinkModel
        The model solved (the period-ν model of a period-ν point).
    harmonics : ndarray (n_coords, 2H+1)
        Real harmonics of the link coordinates on the model's base [m].
    omega : float
        The frequency the model's receptances take [rad/s].

    Returns
    -------
    dict
        In the table's order (:func:`output_names`).
    """
    return points_outputs(model, [harmonics], [omega])[0]


def points_outputs(model, harmonics, omegas, known: dict | None = None) -> list[dict[str, float]]:
    """:func:`point_outputs` of many points: a link with ``metrics_of_points`` (a gear mesh)
    takes all points of one H at once, the bearings' statistics too
    (:func:`~nlgrd.nonlinear.results.bearing_loads.link_bearing_outputs_of_points`).

    Parameters
    ----------
    model : nlgrd.nonlinear.models.link_model.LinkModel
        The model solved (the period-ν model of period-ν points).
    harmonics : sequence of ndarray (n_coords, 2H+1)
        Real harmonics of the link coordinates of each point on the model's base [m].
    omegas : sequence of float
        The frequencies the model's receptances take [rad/s].
    known : dict, optional
        Outputs already computed, per link name a list of dicts (one per point): that
        link's metrics are not computed again (a sweep's own metrics of its first mesh).

    Returns
    -------
    list of dict
        One per point, in the order of :func:`output_names`.
    """
    known = known or {}
    zs = [np.asarray(z, dtype=float) for z in harmonics]
    ws = np.asarray(omegas, dtype=float)
    rows: list[dict[str, float]] = [{} for _ in zs]
    for link, sl in zip(model.links, model.receptance.slices, strict=True):
        if link.name in known:
            for row, m in zip(rows, known[link.name], strict=True):
                row.update({f"{link.name}.{k}": v for k, v in m.items()})
            continue
        batch = getattr(link, "metrics_of_points", None)
        for width in sorted({z.shape[1] for z in zs}):
            idx = [i for i, z in enumerate(zs) if z.shape[1] == width]
            if batch is not None:
                ms = batch(np.stack([zs[i][sl] for i in idx]), ws[idx])
            else:
                ms = [link.metrics(zs[i][sl], float(ws[i])) for i in idx]
            for i, m in zip(idx, ms, strict=True):
                rows[i].update({f"{link.name}.{k}": v for k, v in m.items()})
    for row, b in zip(rows, link_bearing_outputs_of_points(model, zs, ws), strict=True):
        row.update(b)
    return rows


def mesh_amplitudes(model, res: SweepResult, usable: NDArray) -> pd.DataFrame:
    """Every gear mesh's DTE harmonic amplitudes |δ_k| = sqrt(a_k² + b_k²) at k ω, k = 0..H
    (ω the sweep's frequency, H :attr:`SweepResult.H`; k = 0 the mean's magnitude), from the
    points' harmonics on ω/``base`` (every ``base``-th of them): the one-mesh table's
    ``dte_amp_k``, per mesh.

    Parameters
    ----------
    model : nlgrd.nonlinear.models.link_model.LinkModel
        The model whose links and slices of the coordinates are used.
    res : SweepResult
        The points (harmonics of all link coordinates).
    usable : ndarray of bool
        Per point: whether it has outputs (NaN elsewhere).

    Returns
    -------
    pandas.DataFrame
        One row per point, ``<mesh>.dte_amp_<k> [m]`` columns.
    """
    ok = np.asarray(usable, dtype=bool)
    base, H = int(res.base), int(res.H)
    cols: dict[str, NDArray] = {}
    for link, sl in zip(model.links, model.receptance.slices, strict=True):
        if getattr(link, "kind", "") != "gear mesh":
            continue
        z = np.asarray(res.harmonics, dtype=float)[:, sl.start, :]
        amp = np.abs(real_to_complex(z))[:, ::base][:, : H + 1]
        amp[~ok] = np.nan
        cols.update({f"{link.name}.dte_amp_{k} [m]": amp[:, k] for k in range(amp.shape[1])})
    return pd.DataFrame(cols, index=range(len(ok)))


def with_amplitudes(links: pd.DataFrame, model, res: SweepResult, usable: NDArray) -> pd.DataFrame:
    """``links`` with every gear mesh's :func:`mesh_amplitudes` after its columns.

    Parameters
    ----------
    links : pandas.DataFrame
        One row per point of ``res``: ``<link>.<quantity>`` columns.
    model, res, usable
        As :func:`mesh_amplitudes`.

    Returns
    -------
    pandas.DataFrame
    """
    amps = mesh_amplitudes(model, res, usable)
    return pd.concat([links.reset_index(drop=True), amps], axis=1) if amps.shape[1] else links


def link_rows(model, res: SweepResult, usable: NDArray) -> pd.DataFrame:
    """Every link's outputs at the period-1 points of ``res`` (NaN where not ``usable``).

    Parameters
    ----------
    model : nlgrd.nonlinear.models.link_model.LinkModel
        The model whose links and slices of the coordinates are used.
    res : SweepResult
        The points (harmonics of all link coordinates on the model's base).
    usable : ndarray of bool
        Per point: whether it has outputs.

    Returns
    -------
    pandas.DataFrame
        One row per point, ``<link>.<quantity>`` columns.
    """
    blank = dict.fromkeys(output_names(model), np.nan)
    pts = [i for i in range(len(res)) if usable[i]]
    done = dict(zip(pts, points_outputs(model, [res.harmonics[i] for i in pts], res.omega[pts]), strict=True))
    return pd.DataFrame([done.get(i, blank) for i in range(len(res))], columns=list(blank))


@dataclass(frozen=True)
class LinkContinuationResult:
    """A continuation curve of a link model with every link's outputs along it.

    Attributes
    ----------
    curve : ContinuationResult
        The curve (stable and unstable parts, turning points).
    links : pandas.DataFrame
        One row per curve point: ``<link>.<quantity>`` columns, for stable and unstable
        points alike (the curve's ``stable`` column tells which), in SI units.
    speed_per_base, speed_unit
        As :class:`LinkSweepResult`'s.
    """

    curve: ContinuationResult
    links: pd.DataFrame
    speed_per_base: float | None = None
    speed_unit: str = "Hz"

    @property
    def omega(self) -> NDArray:
        """Base frequencies along the curve [rad/s]."""
        return self.curve.omega

    def to_frame(self) -> pd.DataFrame:
        """The curve's table (frequency column ``base_frequency [Hz]``) with the link columns.

        Returns
        -------
        pandas.DataFrame
        """
        frame = with_links(self.curve.to_frame(), self.links)
        return with_speed(frame, self.omega, self.speed_per_base, self.speed_unit)

    def plot(self, quantity: str | None = None, ax=None):
        """One link's output along the curve, stable solid and unstable dashed
        (:func:`nlgrd.plotting.nonlinear.plot_continuation`), against the base frequency.

        Parameters
        ----------
        quantity : str, optional
            ``LINK.QUANTITY`` or a bare quantity (:func:`link_column`); default a mesh's
            DSLR, else the first link's largest force.
        ax : matplotlib.axes.Axes, optional
            Axes to draw on; a new figure when None.

        Returns
        -------
        matplotlib.axes.Axes
        """
        from dataclasses import replace

        from nlgrd.plotting.nonlinear import plot_continuation

        column = link_column(self.links, quantity)
        table = written_frame(self.links[[column]])  # the column as the table writes it
        column = str(table.columns[0])
        points = self.curve.curve
        metrics = {**points.metrics, column: table[column].to_numpy()}
        curve = replace(self.curve, curve=replace(points, metrics=metrics))
        return plot_continuation(curve, quantity=column, ax=ax, xaxis=("base frequency [Hz]", 1.0))

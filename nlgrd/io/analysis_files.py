"""The files of the linear analyses: modes, Campbell diagram and the LSTE of a gear pair.

``nlgrd modes``, ``nlgrd campbell``, ``nlgrd lste`` and the model reports
(:mod:`nlgrd.studies.reports`) write them through these functions: CSV tables and PNG
figures named after the model (``<stem>_modes.csv`` ...), written atomically and together
(:class:`~nlgrd.io.command_line.Outputs`). The figures are drawn by :mod:`nlgrd.plotting`.
"""

from __future__ import annotations

from pathlib import Path
from typing import NamedTuple

from nlgrd.io.command_line import Outputs, pyplot

__all__ = ["LsteFiles", "write_campbell", "write_lste", "write_modes"]


def write_modes(result, folder: Path, stem: str) -> tuple[Path, Path]:
    """Write ``<stem>_modes.csv`` (the table of modes) and ``<stem>_modes.png`` (the first
    six mode shapes, :func:`nlgrd.plotting.rotor.plot_mode_shapes`).

    Parameters
    ----------
    result : ModalResult
        The modes (:func:`nlgrd.rotor.modal.modal_analysis`).
    folder : pathlib.Path
        The output folder (made when missing).
    stem : str
        The files' name stem, the model file's.

    Returns
    -------
    (pathlib.Path, pathlib.Path)
        The CSV and the PNG written.
    """
    from nlgrd.plotting.rotor import plot_mode_shapes

    csv, png = folder / f"{stem}_modes.csv", folder / f"{stem}_modes.png"
    pyplot()
    with Outputs() as out:
        out.csv(result.to_frame(), csv)
        out.figure(plot_mode_shapes(result).flat[0].figure, png)
        out.commit()
    return csv, png


def write_campbell(result, folder: Path, stem: str) -> tuple[Path, Path, Path]:
    """Write ``<stem>_campbell.csv`` (frequencies against speed),
    ``<stem>_critical_speeds.csv`` and ``<stem>_campbell.png``.

    Parameters
    ----------
    result : CampbellResult
        The Campbell diagram (:func:`nlgrd.rotor.modal.campbell`).
    folder : pathlib.Path
        The output folder (made when missing).
    stem : str
        The files' name stem, the model file's.

    Returns
    -------
    (pathlib.Path, pathlib.Path, pathlib.Path)
        The frequencies' CSV, the critical speeds' CSV and the PNG written.
    """
    csv, crit, png = (folder / f"{stem}_{s}" for s in ("campbell.csv", "critical_speeds.csv", "campbell.png"))
    pyplot()
    with Outputs() as out:
        out.csv(result.to_frame(), csv)
        out.csv(result.critical_frame(), crit)
        ax = result.plot()
        ax.figure.tight_layout()
        out.figure(ax.figure, png)
        out.commit()
    return csv, crit, png


class LsteFiles(NamedTuple):
    """What :func:`write_lste` wrote.

    Attributes
    ----------
    csv, png : pathlib.Path
        The table and the figure.
    summary : str
        Where the LSTE came from and its peak-to-peak value, one clause.
    computed : float or None
        The mean mesh stiffness computed from the geometry [N/m]; None when not computed (an
        ``lste_file`` without a static load).
    """

    csv: Path
    png: Path
    summary: str
    computed: float | None


def write_lste(mesh, folder: Path, stem: str) -> LsteFiles:
    """Write ``<stem>_lste.csv`` and ``<stem>_lste.png``: the LSTE of the gear pair that the
    dynamics use, its ``lste_file`` when it has one (the one computed from the geometry
    drawn beside it), else computed from the geometry with the mesh stiffness and the load
    sharing.

    Parameters
    ----------
    mesh : GearMesh
        The gear pair.
    folder : pathlib.Path
        The output folder (made when missing).
    stem : str
        The files' name stem, the model file's.

    Returns
    -------
    LsteFiles
    """
    from nlgrd.plotting.gear import plot_lste_panels

    csv, png = folder / f"{stem}_lste.csv", folder / f"{stem}_lste.png"
    pyplot()
    with Outputs() as out:
        if mesh.lste_file:
            summary, computed = _lste_from_file(mesh, out, csv, png)
        else:
            res = mesh.lste_result()
            computed = res.k_mean
            out.csv(res.to_frame(), csv)
            out.figure(plot_lste_panels(res)[0].figure, png)
            summary = (
                f"LSTE computed from the geometry, peak-to-peak {res.fluctuation_pp * 1e6:.3f} um, "
                f"mean mesh stiffness {res.k_mean:.4g} N/m"
            )
        out.commit()
    return LsteFiles(csv, png, summary, computed)


def _lste_from_file(mesh, out: Outputs, csv: Path, png: Path) -> tuple[str, float | None]:
    """CSV and plot of the LSTE of the gear pair's ``lste_file`` (the one the dynamics use)."""
    import numpy as np
    import pandas as pd

    from nlgrd.gear.lste_file import read_excitation
    from nlgrd.plotting.gear import plot_lste_file

    ex = read_excitation(mesh.lste_file, teeth_pinion=mesh.geometry.teeth_pinion)
    phase = np.arange(mesh.lste_points) / mesh.lste_points
    lste = np.asarray(ex.value(phase))
    out.csv(
        pd.DataFrame(
            {
                "phase [cycles]": phase,
                "pinion_rotation [rad]": 2 * np.pi * phase / mesh.geometry.teeth_pinion,
                "lste [um]": lste * 1e6,
            }
        ),
        csv,
    )
    res = mesh.lste_result() if mesh.static_load > 0 else None
    ax = plot_lste_file(phase, lste, Path(mesh.lste_file).name, computed=res)
    out.figure(ax.figure, png)
    summary = (
        f"LSTE from the lste_file {mesh.lste_file} (the dynamics remove its mean), "
        f"peak-to-peak {ex.peak_to_peak * 1e6:.3f} um"
    )
    return summary, None if res is None else res.k_mean

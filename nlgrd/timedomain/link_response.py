"""The time response of a link model at one base frequency: the last period of every link
coordinate (:class:`LinkTimeResponse`, what :func:`nlgrd.timedomain.links.link_time_response`
returns), its table and its figure."""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from nlgrd.nonlinear.fourier.harmonics import analyse

if TYPE_CHECKING:
    from nlgrd.nonlinear.models.link_model import LinkModel

__all__ = ["LinkTimeResponse", "coordinate_names"]


@dataclass(frozen=True)
class LinkTimeResponse:
    """The last period of a time integration of a link model.

    Attributes
    ----------
    omega : float
        Base frequency [rad/s].
    y : ndarray (d, steps_per_period)
        Link coordinates over the last period [m].
    converged : bool
        A periodic steady state was reached.
    periods : int
        Periods simulated.
    difference : float
        Last relative period-to-period difference of y [-].
    state : tuple of ndarray
        (q, q', q'') at the end, to continue a sweep.
    q : ndarray (len(output_dofs), steps_per_period)
        The requested DOFs over the last period [m, rad].
    names : tuple of str
        ``<link>.<coordinate>`` of each row of ``y`` (default ``y0``, ``y1``, ...).
    """

    omega: float
    y: NDArray
    converged: bool
    periods: int
    difference: float
    state: tuple
    q: NDArray
    names: tuple = ()

    @property
    def t(self) -> NDArray:
        """Time from the start of the last period at each sample [s]."""
        ns = self.y.shape[1]
        return np.arange(ns) * (2 * np.pi / self.omega) / ns

    def to_frame(self):
        """The last period as a table: ``time [s]`` and each link coordinate
        ``<link>.<coordinate> [um]``.

        Returns
        -------
        pandas.DataFrame
        """
        import pandas as pd

        names = self.names or tuple(f"y{i}" for i in range(self.y.shape[0]))
        return pd.DataFrame(
            {"time [s]": self.t, **{f"{n} [um]": v * 1e6 for n, v in zip(names, self.y, strict=True)}}
        )

    def plot(self, ax=None):
        """Every link coordinate over the last period against time
        (:func:`nlgrd.plotting.nonlinear.plot_link_history`).

        Parameters
        ----------
        ax : matplotlib.axes.Axes, optional
            Axes to draw on; a new figure when None.

        Returns
        -------
        matplotlib.axes.Axes
        """
        from nlgrd.plotting.nonlinear import plot_link_history

        return plot_link_history(self.to_frame(), ax=ax)

    def harmonics(self, H: int) -> NDArray:
        """Real harmonics (d, 2H+1) of the link coordinates over the last period [m].

        Parameters
        ----------
        H : int
            Number of harmonics [-].

        Returns
        -------
        ndarray (d, 2H+1)
        """
        return analyse(self.y, H)


def coordinate_names(model: LinkModel) -> tuple[str, ...]:
    """``<link>.<coordinate>`` of every link coordinate of ``model``, in the solver's order.

    Parameters
    ----------
    model : LinkModel
        The model.

    Returns
    -------
    tuple of str
    """
    return tuple(
        f"{lk.name}.{c}"
        for lk in model.links
        for c in getattr(lk, "coordinates", tuple(str(i) for i in range(lk.n_coords)))
    )

"""Plotting: every matplotlib call of nlgrd lives in this package.

Each function takes ``ax=None`` (a new figure when None) and returns the axes.
Submodules: :mod:`.rotor` (modes, Campbell, frequency response, static deflection),
:mod:`.gear` (transmission error, mesh stiffness, load sharing),
:mod:`.nonlinear` (sweeps, continuation curves, time histories),
:mod:`.result_figures` (Floquet multipliers, bearing loads, tori, orbits found by a search),
:mod:`.sweep_figures` (the composed figures of ``nlgrd sweep``: a link sweep with its
branches, the spectra of one point), :mod:`.studies` (study maps, curves, distributions),
:mod:`.common` (the conventions all figures share: colours per sweep direction,
stability, non-converged and off-scale points, legends), :mod:`.figure_files` (drawing
without a display, saving a figure with its caption).
The report index, ``reports/index.html``, is written by :mod:`nlgrd.studies.index_page`.

``headless``, ``record_caption`` and ``save_figure`` of :mod:`.figure_files` are
available here; they are imported on first use, so importing this package does not load
pyplot.
"""

__all__ = ["headless", "record_caption", "save_figure"]


def __getattr__(name: str):
    if name in __all__:
        from nlgrd.plotting import figure_files

        return getattr(figure_files, name)
    raise AttributeError(f"module 'nlgrd.plotting' has no attribute {name!r}")

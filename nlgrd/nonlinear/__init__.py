"""Nonlinear periodic response, in layers (lowest first): fourier, laws, results, links,
reduction, hb, stability, tracing, models (docs/conventions.md)."""

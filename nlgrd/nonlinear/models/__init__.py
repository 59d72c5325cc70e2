"""The model builders: the geared FE model, the link model, the single-DOF model, shaft orders."""

"""The model builders: the link model (every FE model), its views, the single-DOF model, shaft orders."""

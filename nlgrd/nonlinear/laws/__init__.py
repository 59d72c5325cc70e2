"""The nonlinear force laws: backlash and clearance laws, describing functions, the mesh law."""

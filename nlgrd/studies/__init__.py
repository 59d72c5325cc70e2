"""Case studies: experimental data of the literature and the report job."""

"""The link contract (gear meshes, bearing clearances) and the frequency plan of a model."""

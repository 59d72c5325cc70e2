"""What an analysis returns: sweep results, per-point metrics, response kinds, jumps, loads."""

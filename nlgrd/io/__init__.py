"""Model files, their checks, and the command line's options and atomic outputs."""

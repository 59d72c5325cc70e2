"""The linear rotor: materials, shaft elements, disks, bearings and couplings, their
assembly, rigid-body modes, modal analysis and frequency response."""

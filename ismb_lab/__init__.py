"""ismb_lab: a teaching workbench for Hopfield-network stereo matching (ISMB)."""

__version__ = "0.1.0"

"""What every stage shares: one validation format, safe outputs, image headers and numba's cache."""

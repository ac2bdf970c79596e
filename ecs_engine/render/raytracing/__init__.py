"""Ray-traced shadows: the top-level instances, the trace, its mask and denoise."""

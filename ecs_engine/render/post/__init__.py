"""Post effects on the HDR colour before the tone map, each a module that adds its passes to
the frame graph with one call (bloom.py: `add_bloom`)."""

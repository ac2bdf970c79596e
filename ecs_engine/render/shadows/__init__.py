"""Shadow maps: the views per light, their descriptor sets, the maps' pass and the indirect mode's
GPU-culled views."""

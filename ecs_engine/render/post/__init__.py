"""Post-processing effects, each a plugin of the frame graph: its own module and shaders, added
to a graph with one call."""

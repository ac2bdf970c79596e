"""The frame's passes besides the mesh rows: sky, set-aside rows, weighted transparency, light
billboards, the tone map and the output's post-effect stage."""

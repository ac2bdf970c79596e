"""Post effects, each a module that registers itself in registry.py (bloom_effect.py: "bloom"
before the tone map; fxaa_effect.py: "fxaa" after it) and adds its passes to a frame graph;
`Renderer.set_post_effects({"bloom"})` turns them on (docs/post-processing.md)."""

"""What scenes are made of: meshes (data, loading, levels of detail, the GPU registry), materials,
textures (and their GPU pages), primitives and the scene files' asset codecs."""

"""The extract stage: the functions that turn the World into the frame's snapshot (FrameData,
frame_data.py), the only render code that reads the World (tests/test_extract_stage.py holds the
others to it). Each reads only what it names, so that each can become a system of the parallel
schedule (each module's READS is what a system running it declares; tests/test_extract_stage.py
runs each so, where an undeclared query or get fails):

- camera.py: camera_matrices (extract_camera): the active camera's Camera and Transform;
- views.py: extract_views: every camera that draws (Viewport, RenderTexture, RenderLayers),
  with its rectangle and matrices;
- lights.py: extract_lights: the point, spot and directional lights with a Transform;
- shadows.py: ShadowExtract / extract_shadow_casters: the lights with a Shadow;
- environment.py: extract_environment: the Environment resource;
- materials.py: extract_materials: the Materials resource;
- chunks.py: ChunkExtract: the rows with a ModelMatrix and a Mesh (and their shadow tags).

The render origin (components.render_origin) and temporal culling's masks
(temporal_culling.py: ModelMatrix and Mesh columns, the SpeedLimits resource) are read by
FrameExtractor as well. Passes take the snapshot only.
"""

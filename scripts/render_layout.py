"""The sub-package layout of ecs_engine/render/ (issue 36): which module goes where, the packages'
docstrings, the names games import from ecs_engine.render, and the edits a move needs beyond
renames. scripts/move_render.py applies it; tests/test_render_layout.py holds the tree to it."""

from __future__ import annotations

# old module (top level of render/) -> new module under render/; a missing file is skipped
MOVES: dict[str, str] = {
    # the frame: the renderer and what it owns per frame slot
    "renderer": "frame.renderer",
    "frame_resources": "frame.resources",
    "frame_replay": "frame.replay",
    "frame_jobs": "frame.jobs",
    "path_settings": "frame.path_settings",
    "camera": "frame.camera",
    "output_passes": "frame.output_passes",
    "output_barriers": "frame.output_barriers",
    "target_forms": "frame.target_forms",
    "scene_barriers": "frame.scene_barriers",
    "scene_renderings": "frame.scene_renderings",
    "path_pipelines": "draw.path_pipelines",
    # FrameExtractor and FrameData: the extract stage's entry (it reads the World)
    "frame_data": "extract.frame_data",
    # the render paths: the mesh rows' draws (the interface and its implementations)
    "path": "draw.path",
    "chunk_paths": "draw.chunk_paths",
    "indirect_path": "draw.indirect_path",
    "indirect_draws": "draw.indirect_draws",
    "instance_rows": "draw.instance_rows",
    "view_recording": "draw.view_recording",
    # the passes besides the mesh rows' own
    "sky_pass": "passes.sky",
    "set_aside_pass": "passes.set_aside",
    "oit_pass": "passes.oit",
    "light_pass": "passes.light_billboards",
    "tone_map": "passes.tone_map",
    "output_ldr": "passes.output_ldr",
    # culling: the methods' machinery beside the methods (culling/occlusion.py is the method)
    "occlusion": "culling.occlusion_passes",
    "temporal_culling": "culling.temporal_culling",
    "temporal_kernels": "culling.temporal_kernels",
    "light_clusters": "lighting.clusters",
    "light_rows": "lighting.rows",
    "deferred_pass": "lighting.deferred",
    "environment": "lighting.environment",
    "environment_maps": "lighting.environment_maps",
    "environment_prefilter": "lighting.environment_prefilter",
    "radiance_hdr": "lighting.radiance_hdr",
    "shadow_pass": "shadows.maps_pass",
    "shadow_views": "shadows.views",
    "shadow_view_sets": "shadows.view_sets",
    "shadow_indirect": "shadows.indirect",
    "ray_shadows": "raytracing.shadows",
    "ray_instances": "raytracing.instances",
    "shadow_mask": "raytracing.mask",
    "shadow_denoise": "raytracing.denoise",
    **{
        m: f"assets.{m}"
        for m in (
            "meshes",
            "mesh_data",
            "mesh_loading",
            "mesh_lod",
            "mesh_registry",
            "lod_error",
            "lod_worker",
            "model_loading",
            "mtl",
            "named_files",
            "primitives",
            "materials",
            "textures",
            "texture_pages",
            "scene_assets",
            "scene_codec_base",
            "scene_meshes",
        )
    },
    **{m: f"ui.{m}" for m in ("imgui_pass", "imgui_images", "imgui_upload")},
    # config.py becomes the package's __init__.py: `ecs_engine.render.config` keeps its name
    "config": "config",
    "config_support": "config.choices",
    "config_flags": "config.flags",
}
# top-level modules that stay: the layouts every package shares, picking (between frames)
STAY = ("__init__", "layouts", "picking")
PACKAGES: dict[str, str] = {
    "frame": "One frame from FrameData to a submitted command buffer: the Renderer, what each frame "
    "slot owns, frame replay, the frame's chunk jobs, the camera's matrices as the frame uses them.",
    "draw": "The render paths that draw the mesh rows: the RenderPath interface (path.py), the CPU-"
    "recorded paths (chunk_paths.py), the indirect path, the instance rows and their recording.",
    "passes": "The frame's passes besides the mesh rows: sky, set-aside rows, weighted transparency, "
    "light billboards, the tone map and the output's post-effect stage.",
    "lighting": "Lights and environment: clustered light lists, the light rows, deferred lighting, the "
    "environment map (its CPU cube maths, GGX prefilter and Radiance .hdr reader).",
    "shadows": "Shadow maps: the views per light, their descriptor sets, the maps' pass and the indirect "
    "mode's GPU-culled views.",
    "raytracing": "Ray-traced shadows: the top-level instances, the trace, its mask and denoise.",
    "assets": "What scenes are made of: meshes (data, loading, levels of detail, the GPU registry), "
    "materials, textures (and their GPU pages), primitives and the scene files' asset codecs.",
    "ui": "Dear ImGui drawn by the engine: its pass, its texture uploads and engine images shown in it.",
}
# names games import (docs, the `ecs-engine new` template), served by ecs_engine.render itself
PUBLIC: dict[str, str] = {
    **dict.fromkeys(("SHADING_MODELS", "Material", "Materials", "materials"), "assets.materials"),
    "Meshes": "assets.meshes",
    **dict.fromkeys(("MeshData", "normalized", "normalized_together"), "assets.mesh_data"),
    **dict.fromkeys(
        ("cube_mesh", "sphere_mesh", "plane_mesh", "cylinder_mesh", "cone_mesh", "torus_mesh"), "assets.primitives"
    ),
    **dict.fromkeys(("Texture", "Textures"), "assets.textures"),
    **dict.fromkeys(("DEFAULT_MODEL", "load_mesh"), "assets.mesh_loading"),
    "load_model": "assets.model_loading",
}
# scripts/ab_frames.py runs old code against new (issue 36's GPU A/B): it tries the new paths,
# then the flat render/ of before the move, then the layout of before issue 13
_AB_OLD = """\
        from ecs_engine.render.mesh_registry import MeshRegistry
        from ecs_engine.render.renderer import Renderer

        return default_schedule, scene_builder, MeshRegistry, Renderer, World, {}
    except ImportError:
"""
_AB_NEW = (
    """\
        from ecs_engine.render.assets.mesh_registry import MeshRegistry
        from ecs_engine.render.frame.renderer import Renderer

        return default_schedule, scene_builder, MeshRegistry, Renderer, World, {}
    except ImportError:
        pass
    try:  # render/ before its sub-packages (issue 36)
        from ecs_engine.app.scenes import default_schedule, scene_builder
        from ecs_engine.ecs.world import World
"""
    + _AB_OLD
)
# edits a move needs beyond renames: (the module whose move needs it, file, old text, new text, why)
FIXUPS = [
    (
        "frame_data",
        "tests/test_extract_stage.py",
        '    "frame_data.py",  # FrameExtractor: hands the world to the extract functions\n',
        "",
        "frame_data.py is inside extract/ now, whose every module is checked to read the world",
    ),
    ("renderer", "scripts/ab_frames.py", _AB_OLD, _AB_NEW, "old code against new: the new paths, then the old"),
]
# files that name the old paths on purpose (after their fix-ups): never renamed, nor checked
# (they run older trees too: old against new)
KEEP_OLD_PATHS = ("scripts/ab_frames.py", "bench/gpu_memory.py", "bench/lights.py", "bench/bytecodes.py")

"""Every layout the CPU and the shaders share, declared once (see gpu/layout.py): the NumPy dtypes
below are what the engine writes, and shaders/layouts.glsl is generated from them.

Set 0 is the frame's (globals, lights, instance rows, materials, texture pages), shared by every pass and path;
set 1 belongs to the indirect path (ids, key table, draw state, commands); set 2 to its
occlusion culling (last frame's visibility per row, the depth pyramid, the early depth image).
"""

from __future__ import annotations

import numpy as np

from ..components.shadow import SHADOW_HARD, SHADOW_PCF, SHADOW_PCSS  # noqa: F401 (in DEFINES by name)
from ..gpu.layout import Struct, glsl_header

# A mesh vertex as the vertex buffers hold it (tightly packed: vertex input, not a buffer block);
# the pipelines take the stride and attribute offsets from here (chunk_paths.VERTEX_INPUTS names
# the fields mesh_vertex.glsl reads). 48 bytes; 24 before texture coordinates and tangents.
MESH_VERTEX = np.dtype(
    [
        ("position", np.float32, 3),
        ("normal", np.float32, 3),
        ("uv", np.float32, 2),  # (0, 0): the image's top-left corner
        ("tangent", np.float32, 4),  # xyz along +u, w: handedness (mesh_data.py)
    ]
)
UINT_BYTES = np.dtype(np.uint32).itemsize  # one visible-row id, one per-key counter (indirect path)

GLOBALS = Struct(
    "Globals",
    [
        ("projection", "mat4", "reverse-Z: near -> depth 1, far/infinity -> 0"),
        ("view", "mat4", "rotation, and the translation from the render origin to the camera"),
        ("eye", "vec4", "xyz: the camera relative to the render origin (zero by default)"),
        ("ambient", "vec4", "rgb, intensity"),
        ("counts", "uvec4", "x: lights, y: point and spot lights (first in the buffer, drawn as billboards)"),
        ("inverse_projection", "mat4", "the light grid's tile planes, the deferred lighting's positions"),
        (
            "light_tiles",
            "uvec4",
            "x tiles across (0: no light grid), y tiles down, z mask words per tile, w tile side in pixels",
        ),
        ("light_bins", "uvec4", "x first uint of the light bounds, y first uint of the tile masks, zw 0"),
        (
            "bin_depth",
            "vec4",
            "x bin near s, y LIGHT_BINS / ln(far / s): bin = floor(ln(max(distance, s) / s) * y); zw viewport size",
        ),
        (
            "environment",
            "vec4",
            "the Environment (environment.glsl): x intensity, y the mip level that holds roughness 1, "
            "z 1: image-based ambient, w 0",
        ),
        (
            "irradiance",
            "vec4[9]",
            "the environment's diffuse light as 9 spherical harmonics (rgb), environment_maps.py",
        ),
    ],
    std140=True,
    doc="The frame's uniforms. Positions are relative to the render origin (the camera, unless\n"
    "RenderOrigin is pinned).",
)

LIGHT = Struct(
    "Light",
    [
        ("position_radius", "vec4", "relative to the render origin; radius (0: unbounded)"),
        ("color_intensity", "vec4", "linear rgb, intensity (directional: illuminance)"),
        ("direction_kind", "vec4", "xyz: where the light shines (spot, directional); w: LIGHT_POINT/SPOT/DIRECTIONAL"),
        (
            "cone",
            "vec4",
            "spot: x cos(outer angle), y 1 / (cos(inner) - cos(outer)); z first shadow view + 1 (0: none), "
            "w views + RAY_PLACE * (place in the ray-traced shadows' mask + 1; 0: none)",
        ),
    ],
    doc="Point and spot lights first (sorted far to near from the camera), then directional ones.",
)

INSTANCE = Struct(
    "Instance",
    [
        ("model", "vec4[3]", "rows of the camera-relative model matrix (the last row is 0 0 0 1)"),
        (
            "misc",
            "uvec4",
            "x: material index, y: key = mesh * 2 + mirrored, z: 1 NotShadowReceiver, "
            "w: bit 0 ROW_NOT_CASTER (indirect mode), bits 1-31 a skinned row's first joint + 1 "
            "(extract/skins.py), else 0",
        ),
    ],
    doc="One entity's row: 64 bytes (the normal matrix is derived in the vertex shader).",
)

MATERIAL = Struct(
    "Material",
    [
        ("base_color", "vec4", "linear rgba"),
        ("emissive", "vec4", "linear rgb, w: 0"),
        ("surface", "vec4", "x metallic, y roughness, z shininess, w specular strength times Material.normalisation"),
        ("params", "vec4", "x alpha cutoff, y normal scale, z occlusion strength, w 0"),
        ("kind", "uvec4", "x shading model (MODEL_*), y ALPHA_* mode, z double-sided, w 0"),
        ("textures", "uvec4", "base colour, metallic-roughness, normal, emissive: page << 16 | layer, or NO_TEXTURE"),
        ("textures2", "uvec4", "x occlusion texture (as above); yzw: NO_TEXTURE"),
        ("environment", "vec4", "x reflectivity, y refraction, z index of refraction, w 0 (environment.glsl)"),
    ],
    doc="A material (render/materials.py): what the fragment shader's shading model reads.",
)

KEY_INFO = Struct(
    "KeyInfo",
    [
        ("index_count", "uint"),
        ("first_index", "uint", "of the mesh in the merged index buffer"),
        ("vertex_offset", "int", "of the mesh in the merged vertex buffer"),
        ("base", "uint", "first slot of this key's region of ids"),
        ("sphere", "vec4", "the mesh's bounding sphere (holding its levels of detail too): centre xyz, radius"),
        ("lod", "uvec4", "x: the draw mesh of its first coarser level (that level's key: x * 2 + mirrored), y: levels"),
        ("lod_error", "vec4", "per coarser level, its error in the mesh's units (render/mesh_lod.py)"),
    ],
    doc="The indirect path's key table: one row per key = draw mesh * 2 + mirrored (the meshes, then their "
    "levels of detail: mesh_registry.py merged).",
)

DRAW_STATE = Struct(
    "DrawStateHeader",
    [
        ("draw_counts", "uint[2]", "commands per winding: the count buffer of vkCmdDrawIndexedIndirectCount"),
        ("pad", "uint[2]"),
    ],
    doc="Head of the indirect path's draw state buffer; visible rows per key follow it.",
)

DRAW_COMMAND = Struct(
    "DrawCommand",
    [
        ("index_count", "uint"),
        ("instance_count", "uint"),
        ("first_index", "uint"),
        ("vertex_offset", "int"),
        ("first_instance", "uint"),
    ],
    doc="VkDrawIndexedIndirectCommand.",
)

CULL_PUSH = Struct(
    "CullPush",
    [
        ("planes", "vec4[6]", "frustum planes (camera-relative, pointing inwards)"),
        ("plane_count", "uint", "0: culling off"),
        ("row_end", "uint", "rows [first_row, row_end) in this dispatch (large counts take several)"),
        ("first_row", "uint"),
        ("skip", "uint", "rows whose misc.w has one of these bits are left out (a shadow view: ROW_NOT_CASTER)"),
        (
            "occlusion",
            "uvec4",
            "the camera's cull passes: xy the target's size (the depth pyramid's base), z the pyramid's "
            "levels, w CULL_* bits",
        ),
    ],
)

# depth_reduce.comp (render/occlusion.py): one level of the depth pyramid from the one below it
REDUCE_PUSH = Struct(
    "ReducePush",
    [
        (
            "source",
            "uvec4",
            "xy the level read (level 0: the depth image's size), z its first float, w the samples (0: a level)",
        ),
        ("target", "uvec4", "xy the level written, z its first float, w 0"),
    ],
)

COMPACT_PUSH = Struct(
    "CompactPush",
    [
        ("key_count", "uint"),
        ("mesh_count", "uint", "commands per winding list"),
    ],
)

BILLBOARD_PUSH = Struct("BillboardPush", [("size", "float", "half the quad's side, in view units")])

TONE_MAP_PUSH = Struct(
    "ToneMapPush",
    [
        ("exposure", "float", "linear scale before the curve (2^EV)"),
        ("operator", "uint", "TONE_MAP_* (render/tone_map.py)"),
    ],
)

SHADOW_VIEW = Struct(
    "ShadowView",
    [
        ("view_projection", "mat4", "render-relative positions -> the shadow map's clip space (reverse-Z)"),
        (
            "params",
            "vec4",
            "x depth bias (NDC; perspective: times 1/w), y normal offset (world; perspective: times w), "
            "z far (a cascade: its slice's far view distance), w softness (PCF: texels; PCSS: light size)",
        ),
        ("info", "uvec4", "x layer, y SHADOW_* filter, z resolution, w 0 orthographic, 1 spot, 2 cube face"),
        (
            "depth_model",
            "vec4",
            "x P22, y P23 of the projection (a light distance from a depth), z a texel's world size "
            "(perspective: at distance 1), w the view's share of its layer across (drawn in its corner)",
        ),
    ],
    doc="One shadow view (render/shadow_views.py): a cascade, a spot light's map, a cube face.",
)

DEFERRED_PUSH = Struct(
    "DeferredPush", [("viewport", "uvec2", "the frame's viewport in pixels (the G-buffer may be larger)")]
)

MAX_RAY_LIGHTS = 8  # shadow-casting lights the ray-traced shadows trace (render/ray_shadows.py)
RAY_PLACE = 16  # Light.cone.w: views (at most 6) + RAY_PLACE * (the light's place in the rays' mask + 1)
RAY_FRAME = Struct(
    "RayFrame",
    [
        ("inverse_projection", "mat4", "clip -> view space (the frame's projection, reverse-Z)"),
        ("view", "mat4", "render-relative positions -> view space (a rotation and a translation)"),
        ("size", "uvec4", "x, y the viewport in pixels, z the lights, w the frame (the samples' noise)"),
        (
            "light_position",
            f"vec4[{MAX_RAY_LIGHTS}]",
            "xyz a point or spot light's render-relative position, a directional light's unit direction "
            "towards it; w its LIGHT_* kind",
        ),
        (
            "light_params",
            f"vec4[{MAX_RAY_LIGHTS}]",
            "x the light's size (point, spot: radius; directional: tangent of its angular radius), "
            "y rays per pixel, z its reach (0: none), w 0",
        ),
    ],
    doc="The ray-traced shadows' frame (render/ray_shadows.py, shaders/shadow_rays.rgen).",
)

IMGUI_PUSH = Struct(
    "ImGuiPush",
    [
        ("scale", "vec2", "2 / display size"),
        ("translate", "vec2", "-1 - display pos * scale"),
    ],
)

SET_FRAME, SET_INDIRECT = 0, 1
BINDING_GLOBALS, BINDING_LIGHTS, BINDING_INSTANCES, BINDING_MATERIALS, BINDING_TEXTURES = 0, 1, 2, 3, 4
BINDING_CLUSTERS = 5  # clustered lights (light_clusters.py): distance bins and tile masks
# shadows (render/shadow_pass.py): the views' rows, the map array with a filtering and a nearest
# comparison sampler (PCF and PCSS; hard shadows), and read as depths (PCSS's blocker search)
BINDING_SHADOW_VIEWS, BINDING_SHADOW_MAP, BINDING_SHADOW_MAP_HARD, BINDING_SHADOW_DEPTH = 6, 7, 8, 9
BINDING_ENVIRONMENT = 10  # the Environment's cube map (a black 1-texel cube without one)
# skinning (render/extract/skins.py, render/assets/skin_vertices.py): the frame's joint matrices
# (3 vec4 rows each) and the skinned meshes' vertex weights, read by the vertex shaders
BINDING_JOINTS, BINDING_SKIN_VERTICES = 11, 12
SKIN_WORDS = 12  # a skinned vertex's record in BINDING_SKIN_VERTICES: 4 words of joint indices, 8 of weights
MORPH_WORDS = 9  # a morph target's vertex there: its position's, normal's and tangent's deltas
TEXTURE_PAGES = 18  # texture_pages.py: two views (sRGB, UNORM) per size class, 16 to 4096 texels
BINDING_IDS, BINDING_KEYS, BINDING_DRAW_STATE, BINDING_COMMANDS = 0, 1, 2, 3
# shading models: the values of Material.kind.x and bits 0-5 of the mesh pipelines' MATERIAL_FEATURES
# specialisation constant (FEATURE_* are its other bits); their names are render/materials.py's
# SHADING_MODELS, in this order
MODEL_UNLIT, MODEL_LAMBERT, MODEL_OREN_NAYAR, MODEL_PHONG, MODEL_BLINN_PHONG, MODEL_COOK_TORRANCE = range(6)
FEATURE_ALPHA_MASK = 1 << 16  # some material is drawn with alpha_mode mask
FEATURE_TEXTURES = 1 << 17  # some material has a texture: the textured shader variants (uv, tangents)
FEATURE_DOUBLE_SIDED = 1 << 18  # some material is double-sided: no back-face culling, see mesh_fragment.glsl
FEATURE_CLUSTERED = 1 << 19  # fragments loop over their cluster's lights, not all (light_clusters.py)
FEATURE_SPOT_LIGHTS = 1 << 20  # the scene has spot lights (without: lights are read as points)
FEATURE_DIRECTIONAL_LIGHTS = 1 << 21  # the scene has directional lights
FEATURE_EMISSIVE = 1 << 22  # some material glows (emissive colour or texture): without, none is read
FEATURE_BLEND = 1 << 23  # some material is alpha-blended: without, every fragment's alpha is 1
FEATURE_SHADOWS = 1 << 24  # some light casts shadows: without, no shadow map is read
FEATURE_ENVIRONMENT = 1 << 25  # the world has an Environment: its sky, reflections and ambient are read
FEATURE_RAY_SHADOWS = 1 << 26  # shadows are ray-traced: the deferred lighting reads their mask, no map
# some row is skinned or morphed: without, the vertex shaders are specialised without deform.glsl's
# code, whose registers slow every vertex even where no row takes it
FEATURE_DEFORM = 1 << 27
CLUSTER_GROUP = 64  # light_bounds.comp's and light_tiles.comp's local size
MAX_GLOBAL_LIGHTS = 256  # directional and unbounded lights every fragment loops over, when clustered
LIGHT_BINS = 1024  # distance bins: exponential shells around the eye, each with its light index range
# the cluster buffer: a header (the global list's count, then the global list), per distance bin
# the lowest then (LIGHT_BINS later) the highest index of a light reaching into it, then per light
# its bounding sphere in view space (4 floats), then per screen tile a bit mask over the lights
CLUSTER_GLOBALS = 4
CLUSTER_HEADER = CLUSTER_GLOBALS + MAX_GLOBAL_LIGHTS
ALPHA_OPAQUE, ALPHA_MASK, ALPHA_BLEND = range(3)
LIGHT_POINT, LIGHT_SPOT, LIGHT_DIRECTIONAL = range(3)
TONE_MAP_CLAMP, TONE_MAP_ACES, TONE_MAP_REINHARD = range(3)
NO_TEXTURE = 0xFFFFFFFF
NO_MATERIAL = 0xFFFFFFFF  # the G-buffer's material index where nothing is lit (gpu/gbuffer.py)
# the deferred lighting pass (render/deferred_pass.py): set 1 names the G-buffer's images
SET_DEFERRED = 1
BINDING_DEPTH, BINDING_HDR, BINDING_NORMAL_ROUGHNESS, BINDING_BASE_METALLIC, BINDING_MATERIAL_IDS = range(5)
BINDING_SHADOW_MASK = 5  # ray-traced shadows' mask: 4 lights a layer, one per channel (render/ray_shadows.py)
# the ray-traced shadows' own set (shaders/shadow_rays.rgen)
BINDING_RAY_SCENE, BINDING_RAY_FRAME, BINDING_RAY_DEPTH, BINDING_RAY_NORMAL, BINDING_RAY_MASK = range(5)
BINDING_RAY_DENOISED = 5  # shadow_denoise.comp's output (the mask the lighting reads)
# the shadow rays' pipeline: the frame set is set 0 (the any-hit shader reads its materials and
# textures, as shadow_cutout.frag does), the rays' own set is set 1
SET_RAY = 1
BINDING_RAY_MESHES = 6  # per mesh handle: its vertex and index buffers' device addresses (uvec4)
BINDING_RAY_ROWS = 7  # per top-level instance: its mesh handle and material (uvec2)
MESH_VERTEX_FLOATS = MESH_VERTEX.itemsize // 4  # a mesh vertex in floats, and its uv's first float
MESH_VERTEX_UV = int(MESH_VERTEX.fields["uv"][1]) // 4 if MESH_VERTEX.fields else 0
DEFERRED_TILE = 16  # a workgroup lights DEFERRED_TILE x DEFERRED_TILE pixels
DEFERRED_WORDS = 512  # light mask words a workgroup holds at once (16,384 lights; more take turns)
CULL_GROUP = 256  # cull.comp's local size
ROW_NOT_CASTER = 1  # Instance.misc.w bit (indirect mode): the row casts no shadow (cull.comp skips it in shadow views)
COMPACT_GROUP = 64  # compact.comp's local size
POSED_GROUP = 64  # posed_vertices.comp's local size
# two-phase occlusion culling (render/occlusion.py): set 2 of the cull passes, set 0 of the reduction
SET_OCCLUSION = 2
BINDING_VISIBILITY, BINDING_PYRAMID, BINDING_EARLY_DEPTH = range(3)
REDUCE_GROUP = 8  # depth_reduce.comp's local size, each way
CULL_SUBPIXEL = 1  # CullPush.occlusion.w: rows covering no pixel centre are culled (occlusion culling)
CULL_LOD = 2  # CullPush.occlusion.w: rows draw the coarsest level of detail their size allows
MAX_LODS = 4  # coarser levels a key table row holds (KeyInfo.lod_error)
# the skinned and morphed meshes' data (render/assets/skin_vertices.py): per mesh, where its skin
# records and morph block start, for the mesh and each coarser level (the indirect mode draws levels)
SKIN_HEADER_WORDS = 2 * (1 + MAX_LODS)
# a visible row's entry in the indirect mode's ids (cull_row.glsl): its index, and the level it is
# drawn at above ROW_LEVEL_SHIFT (a skinned row's vertex shader reads that level's weights)
ROW_LEVEL_SHIFT = 29

STRUCTS = [
    GLOBALS,
    LIGHT,
    INSTANCE,
    MATERIAL,
    KEY_INFO,
    DRAW_STATE,
    DRAW_COMMAND,
    CULL_PUSH,
    COMPACT_PUSH,
    REDUCE_PUSH,
    BILLBOARD_PUSH,
    TONE_MAP_PUSH,
    SHADOW_VIEW,
    DEFERRED_PUSH,
    RAY_FRAME,
    IMGUI_PUSH,
]
# the constants shaders/layouts.glsl defines, in its order (each is this module's name and value;
# a name that is not one fails at import)
_GLSL_NAMES = """
SET_FRAME SET_INDIRECT BINDING_GLOBALS BINDING_LIGHTS BINDING_INSTANCES BINDING_MATERIALS BINDING_TEXTURES
BINDING_CLUSTERS FEATURE_CLUSTERED FEATURE_SPOT_LIGHTS FEATURE_DIRECTIONAL_LIGHTS FEATURE_EMISSIVE FEATURE_BLEND
FEATURE_SHADOWS BINDING_SHADOW_VIEWS BINDING_SHADOW_MAP BINDING_SHADOW_MAP_HARD BINDING_SHADOW_DEPTH
BINDING_ENVIRONMENT FEATURE_ENVIRONMENT BINDING_JOINTS BINDING_SKIN_VERTICES SKIN_WORDS MORPH_WORDS
SHADOW_HARD SHADOW_PCF SHADOW_PCSS CLUSTER_GROUP MAX_GLOBAL_LIGHTS
LIGHT_BINS CLUSTER_HEADER CLUSTER_GLOBALS TEXTURE_PAGES BINDING_IDS BINDING_KEYS BINDING_DRAW_STATE
BINDING_COMMANDS MODEL_UNLIT MODEL_LAMBERT MODEL_OREN_NAYAR MODEL_PHONG MODEL_BLINN_PHONG MODEL_COOK_TORRANCE
FEATURE_ALPHA_MASK FEATURE_TEXTURES FEATURE_DOUBLE_SIDED ALPHA_OPAQUE ALPHA_MASK ALPHA_BLEND LIGHT_POINT
LIGHT_SPOT LIGHT_DIRECTIONAL TONE_MAP_CLAMP TONE_MAP_ACES TONE_MAP_REINHARD NO_TEXTURE NO_MATERIAL SET_DEFERRED
BINDING_DEPTH BINDING_HDR BINDING_NORMAL_ROUGHNESS BINDING_BASE_METALLIC BINDING_MATERIAL_IDS DEFERRED_TILE
DEFERRED_WORDS CULL_GROUP ROW_NOT_CASTER COMPACT_GROUP SET_OCCLUSION BINDING_VISIBILITY BINDING_PYRAMID
BINDING_EARLY_DEPTH REDUCE_GROUP CULL_SUBPIXEL CULL_LOD MAX_LODS MAX_RAY_LIGHTS RAY_PLACE FEATURE_RAY_SHADOWS
FEATURE_DEFORM
BINDING_SHADOW_MASK BINDING_RAY_SCENE BINDING_RAY_FRAME BINDING_RAY_DEPTH BINDING_RAY_NORMAL BINDING_RAY_MASK
BINDING_RAY_DENOISED SET_RAY BINDING_RAY_MESHES BINDING_RAY_ROWS MESH_VERTEX_FLOATS MESH_VERTEX_UV POSED_GROUP
SKIN_HEADER_WORDS ROW_LEVEL_SHIFT
""".split()
DEFINES = {name: globals()[name] for name in _GLSL_NAMES}


def glsl() -> str:
    """The text of shaders/layouts.glsl."""
    return glsl_header(STRUCTS, DEFINES, "ecs_engine/render/layouts.py")

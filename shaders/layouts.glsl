// Generated from ecs_engine/render/layouts.py by scripts/compile_shaders.py: do not edit.
#ifndef LAYOUTS_GLSL
#define LAYOUTS_GLSL

#define SET_FRAME 0
#define SET_INDIRECT 1
#define BINDING_GLOBALS 0
#define BINDING_LIGHTS 1
#define BINDING_INSTANCES 2
#define BINDING_MATERIALS 3
#define BINDING_TEXTURES 4
#define BINDING_CLUSTERS 5
#define FEATURE_CLUSTERED 524288
#define FEATURE_SPOT_LIGHTS 1048576
#define FEATURE_DIRECTIONAL_LIGHTS 2097152
#define FEATURE_EMISSIVE 4194304
#define FEATURE_BLEND 8388608
#define FEATURE_SHADOWS 16777216
#define BINDING_SHADOW_VIEWS 6
#define BINDING_SHADOW_MAP 7
#define BINDING_SHADOW_MAP_HARD 8
#define BINDING_SHADOW_DEPTH 9
#define BINDING_ENVIRONMENT 10
#define FEATURE_ENVIRONMENT 33554432
#define BINDING_JOINTS 11
#define BINDING_SKIN_VERTICES 12
#define SKIN_WORDS 12
#define MORPH_WORDS 9
#define SHADOW_HARD 0
#define SHADOW_PCF 1
#define SHADOW_PCSS 2
#define CLUSTER_GROUP 64
#define MAX_GLOBAL_LIGHTS 256
#define LIGHT_BINS 1024
#define CLUSTER_HEADER 260
#define CLUSTER_GLOBALS 4
#define TEXTURE_PAGES 18
#define BINDING_IDS 0
#define BINDING_KEYS 1
#define BINDING_DRAW_STATE 2
#define BINDING_COMMANDS 3
#define MODEL_UNLIT 0
#define MODEL_LAMBERT 1
#define MODEL_OREN_NAYAR 2
#define MODEL_PHONG 3
#define MODEL_BLINN_PHONG 4
#define MODEL_COOK_TORRANCE 5
#define FEATURE_ALPHA_MASK 65536
#define FEATURE_TEXTURES 131072
#define FEATURE_DOUBLE_SIDED 262144
#define ALPHA_OPAQUE 0
#define ALPHA_MASK 1
#define ALPHA_BLEND 2
#define LIGHT_POINT 0
#define LIGHT_SPOT 1
#define LIGHT_DIRECTIONAL 2
#define TONE_MAP_CLAMP 0
#define TONE_MAP_ACES 1
#define TONE_MAP_REINHARD 2
#define NO_TEXTURE 4294967295u
#define NO_MATERIAL 4294967295u
#define SET_DEFERRED 1
#define BINDING_DEPTH 0
#define BINDING_HDR 1
#define BINDING_NORMAL_ROUGHNESS 2
#define BINDING_BASE_METALLIC 3
#define BINDING_MATERIAL_IDS 4
#define DEFERRED_TILE 16
#define DEFERRED_WORDS 512
#define CULL_GROUP 256
#define ROW_NOT_CASTER 1
#define COMPACT_GROUP 64
#define SET_OCCLUSION 2
#define BINDING_VISIBILITY 0
#define BINDING_PYRAMID 1
#define BINDING_EARLY_DEPTH 2
#define REDUCE_GROUP 8
#define CULL_SUBPIXEL 1
#define CULL_LOD 2
#define MAX_LODS 4
#define MAX_RAY_LIGHTS 8
#define RAY_PLACE 16
#define FEATURE_RAY_SHADOWS 67108864
#define FEATURE_DEFORM 134217728
#define BINDING_SHADOW_MASK 5
#define BINDING_RAY_SCENE 0
#define BINDING_RAY_FRAME 1
#define BINDING_RAY_DEPTH 2
#define BINDING_RAY_NORMAL 3
#define BINDING_RAY_MASK 4
#define BINDING_RAY_DENOISED 5
#define SET_RAY 1
#define BINDING_RAY_MESHES 6
#define BINDING_RAY_ROWS 7
#define MESH_VERTEX_FLOATS 12
#define MESH_VERTEX_UV 6
#define POSED_GROUP 64
#define SKIN_HEADER_WORDS 10
#define ROW_LEVEL_SHIFT 29

// The frame's uniforms. Positions are relative to the render origin (the camera, unless
// RenderOrigin is pinned).
struct Globals {  // 448 bytes, std140
    mat4 projection;            // offset 0: reverse-Z: near -> depth 1, far/infinity -> 0
    mat4 view;                  // offset 64: rotation, and the translation from the render origin to the camera
    vec4 eye;                   // offset 128: xyz: the camera relative to the render origin (zero by default)
    vec4 ambient;               // offset 144: rgb, intensity
    uvec4 counts;               // offset 160: x: lights, y: point and spot lights (first in the buffer, drawn as billboards)
    mat4 inverse_projection;    // offset 176: the light grid's tile planes, the deferred lighting's positions
    uvec4 light_tiles;          // offset 240: x tiles across (0: no light grid), y tiles down, z mask words per tile, w tile side in pixels
    uvec4 light_bins;           // offset 256: x first uint of the light bounds, y first uint of the tile masks, zw 0
    vec4 bin_depth;             // offset 272: x bin near s, y LIGHT_BINS / ln(far / s): bin = floor(ln(max(distance, s) / s) * y); zw viewport size
    vec4 environment;           // offset 288: the Environment (environment.glsl): x intensity, y the mip level that holds roughness 1, z 1: image-based ambient, w 0
    vec4 irradiance[9];         // offset 304: the environment's diffuse light as 9 spherical harmonics (rgb), environment_maps.py
};

// Point and spot lights first (sorted far to near from the camera), then directional ones.
struct Light {  // 64 bytes, std430
    vec4 position_radius;       // offset 0: relative to the render origin; radius (0: unbounded)
    vec4 color_intensity;       // offset 16: linear rgb, intensity (directional: illuminance)
    vec4 direction_kind;        // offset 32: xyz: where the light shines (spot, directional); w: LIGHT_POINT/SPOT/DIRECTIONAL
    vec4 cone;                  // offset 48: spot: x cos(outer angle), y 1 / (cos(inner) - cos(outer)); z first shadow view + 1 (0: none), w views + RAY_PLACE * (place in the ray-traced shadows' mask + 1; 0: none)
};

// One entity's row: 64 bytes (the normal matrix is derived in the vertex shader).
struct Instance {  // 64 bytes, std430
    vec4 model[3];              // offset 0: rows of the camera-relative model matrix (the last row is 0 0 0 1)
    uvec4 misc;                 // offset 48: x: material index, y: key = mesh * 2 + mirrored, z: 1 NotShadowReceiver, w: bit 0 ROW_NOT_CASTER (indirect mode), bits 1-31 a skinned row's first joint + 1 (extract/skins.py), else 0
};

// A material (render/materials.py): what the fragment shader's shading model reads.
struct Material {  // 128 bytes, std430
    vec4 base_color;            // offset 0: linear rgba
    vec4 emissive;              // offset 16: linear rgb, w: 0
    vec4 surface;               // offset 32: x metallic, y roughness, z shininess, w specular strength times Material.normalisation
    vec4 params;                // offset 48: x alpha cutoff, y normal scale, z occlusion strength, w 0
    uvec4 kind;                 // offset 64: x shading model (MODEL_*), y ALPHA_* mode, z double-sided, w 0
    uvec4 textures;             // offset 80: base colour, metallic-roughness, normal, emissive: page << 16 | layer, or NO_TEXTURE
    uvec4 textures2;            // offset 96: x occlusion texture (as above); yzw: NO_TEXTURE
    vec4 environment;           // offset 112: x reflectivity, y refraction, z index of refraction, w 0 (environment.glsl)
};

// The indirect path's key table: one row per key = draw mesh * 2 + mirrored (the meshes, then their levels of detail: mesh_registry.py merged).
struct KeyInfo {  // 64 bytes, std430
    uint index_count;           // offset 0
    uint first_index;           // offset 4: of the mesh in the merged index buffer
    int vertex_offset;          // offset 8: of the mesh in the merged vertex buffer
    uint base;                  // offset 12: first slot of this key's region of ids
    vec4 sphere;                // offset 16: the mesh's bounding sphere (holding its levels of detail too): centre xyz, radius
    uvec4 lod;                  // offset 32: x: the draw mesh of its first coarser level (that level's key: x * 2 + mirrored), y: levels
    vec4 lod_error;             // offset 48: per coarser level, its error in the mesh's units (render/mesh_lod.py)
};

// Head of the indirect path's draw state buffer; visible rows per key follow it.
struct DrawStateHeader {  // 16 bytes, std430
    uint draw_counts[2];        // offset 0: commands per winding: the count buffer of vkCmdDrawIndexedIndirectCount
    uint pad[2];                // offset 8
};

// VkDrawIndexedIndirectCommand.
struct DrawCommand {  // 20 bytes, std430
    uint index_count;           // offset 0
    uint instance_count;        // offset 4
    uint first_index;           // offset 8
    int vertex_offset;          // offset 12
    uint first_instance;        // offset 16
};

struct CullPush {  // 128 bytes, std430
    vec4 planes[6];             // offset 0: frustum planes (camera-relative, pointing inwards)
    uint plane_count;           // offset 96: 0: culling off
    uint row_end;               // offset 100: rows [first_row, row_end) in this dispatch (large counts take several)
    uint first_row;             // offset 104
    uint skip;                  // offset 108: rows whose misc.w has one of these bits are left out (a shadow view: ROW_NOT_CASTER)
    uvec4 occlusion;            // offset 112: the camera's cull passes: xy the target's size (the depth pyramid's base), z the pyramid's levels, w CULL_* bits
};

struct CompactPush {  // 8 bytes, std430
    uint key_count;             // offset 0
    uint mesh_count;            // offset 4: commands per winding list
};

struct ReducePush {  // 32 bytes, std430
    uvec4 source;               // offset 0: xy the level read (level 0: the depth image's size), z its first float, w the samples (0: a level)
    uvec4 target;               // offset 16: xy the level written, z its first float, w 0
};

struct BillboardPush {  // 4 bytes, std430
    float size;                 // offset 0: half the quad's side, in view units
};

struct ToneMapPush {  // 8 bytes, std430
    float exposure;             // offset 0: linear scale before the curve (2^EV)
    uint operator;              // offset 4: TONE_MAP_* (render/tone_map.py)
};

// One shadow view (render/shadow_views.py): a cascade, a spot light's map, a cube face.
struct ShadowView {  // 112 bytes, std430
    mat4 view_projection;       // offset 0: render-relative positions -> the shadow map's clip space (reverse-Z)
    vec4 params;                // offset 64: x depth bias (NDC; perspective: times 1/w), y normal offset (world; perspective: times w), z far (a cascade: its slice's far view distance), w softness (PCF: texels; PCSS: light size)
    uvec4 info;                 // offset 80: x layer, y SHADOW_* filter, z resolution, w 0 orthographic, 1 spot, 2 cube face
    vec4 depth_model;           // offset 96: x P22, y P23 of the projection (a light distance from a depth), z a texel's world size (perspective: at distance 1), w the view's share of its layer across (drawn in its corner)
};

struct DeferredPush {  // 8 bytes, std430
    uvec2 viewport;             // offset 0: the frame's viewport in pixels (the G-buffer may be larger)
};

// The ray-traced shadows' frame (render/ray_shadows.py, shaders/shadow_rays.rgen).
struct RayFrame {  // 400 bytes, std430
    mat4 inverse_projection;    // offset 0: clip -> view space (the frame's projection, reverse-Z)
    mat4 view;                  // offset 64: render-relative positions -> view space (a rotation and a translation)
    uvec4 size;                 // offset 128: x, y the viewport in pixels, z the lights, w the frame (the samples' noise)
    vec4 light_position[8];     // offset 144: xyz a point or spot light's render-relative position, a directional light's unit direction towards it; w its LIGHT_* kind
    vec4 light_params[8];       // offset 272: x the light's size (point, spot: radius; directional: tangent of its angular radius), y rays per pixel, z its reach (0: none), w 0
};

struct ImGuiPush {  // 16 bytes, std430
    vec2 scale;                 // offset 0: 2 / display size
    vec2 translate;             // offset 8: -1 - display pos * scale
};

#endif

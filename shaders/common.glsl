// The frame's set (0), shared by every pass and render path. The structs and binding numbers
// come from layouts.glsl, generated from ecs_engine/render/layouts.py (the CPU's dtypes).
// Matrices come from NumPy [row, col] arrays uploaded transposed, so they arrive column-major
// as GLSL expects.
#include "layouts.glsl"

layout(std140, set = SET_FRAME, binding = BINDING_GLOBALS) uniform GlobalsBlock { Globals g; };
layout(std430, set = SET_FRAME, binding = BINDING_LIGHTS) readonly buffer Lights { Light lights[]; };
layout(std430, set = SET_FRAME, binding = BINDING_INSTANCES) readonly buffer Instances { Instance instances[]; };
layout(std430, set = SET_FRAME, binding = BINDING_MATERIALS) readonly buffer Materials { Material materials[]; };
#ifndef CLUSTER_WRITER
layout(std430, set = SET_FRAME, binding = BINDING_CLUSTERS) readonly buffer Clusters { uint cluster_data[]; };
#endif
// shadows (render/shadow_pass.py): bound always, a 1-texel map when no light casts
layout(std430, set = SET_FRAME, binding = BINDING_SHADOW_VIEWS) readonly buffer ShadowViews { ShadowView shadow_views[]; };
layout(set = SET_FRAME, binding = BINDING_SHADOW_MAP) uniform sampler2DArrayShadow shadow_map;
layout(set = SET_FRAME, binding = BINDING_SHADOW_MAP_HARD) uniform sampler2DArrayShadow shadow_map_hard;
layout(set = SET_FRAME, binding = BINDING_SHADOW_DEPTH) uniform sampler2DArray shadow_depth;
// the Environment's cube map (render/environment.py): bound always, a black 1-texel cube without one
layout(set = SET_FRAME, binding = BINDING_ENVIRONMENT) uniform samplerCube environment_map;

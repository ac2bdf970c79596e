#version 450
#extension GL_GOOGLE_include_directive : require
// One level of the depth pyramid (render/occlusion.py, occlusion.glsl): each texel the minimum
// (reverse-Z: the farthest) of the 2 x 2 texels below it, those past the edge left out; level 0
// reads the early depth image.
#include "layouts.glsl"

layout(local_size_x = REDUCE_GROUP, local_size_y = REDUCE_GROUP) in;
layout(push_constant) uniform Reduce { ReducePush pc; };
layout(std430, set = SET_OCCLUSION, binding = BINDING_PYRAMID) buffer Pyramid { float pyramid[]; };
layout(set = SET_OCCLUSION, binding = BINDING_EARLY_DEPTH) uniform sampler2D early_depth;

float source(uvec2 p) {
    if (pc.source.w != 0u) return texelFetch(early_depth, ivec2(p), 0).r;
    return pyramid[pc.source.z + p.y * pc.source.x + p.x];
}

void main() {
    uvec2 t = gl_GlobalInvocationID.xy;
    if (t.x >= pc.target.x || t.y >= pc.target.y) return;
    uvec2 p0 = t * 2u;
    uvec2 p1 = min(p0 + 1u, pc.source.xy - 1u);
    float m = min(min(source(p0), source(uvec2(p1.x, p0.y))), min(source(uvec2(p0.x, p1.y)), source(p1)));
    pyramid[pc.target.z + t.y * pc.target.x + t.x] = m;
}

// One level of the depth pyramid (render/occlusion.py, occlusion.glsl): each texel the minimum
// (reverse-Z: the farthest) of the 2 x 2 texels below it, those past the edge left out; level 0
// reads the early depth image (pc.source.w: its samples; depth_reduce_ms.comp, MULTISAMPLED,
// takes the farthest of every sample of a pixel).
#include "layouts.glsl"

layout(local_size_x = REDUCE_GROUP, local_size_y = REDUCE_GROUP) in;
layout(push_constant) uniform Reduce { ReducePush pc; };
layout(std430, set = SET_OCCLUSION, binding = BINDING_PYRAMID) buffer Pyramid { float pyramid[]; };
#ifdef MULTISAMPLED
layout(set = SET_OCCLUSION, binding = BINDING_EARLY_DEPTH) uniform sampler2DMS early_depth;
#else
layout(set = SET_OCCLUSION, binding = BINDING_EARLY_DEPTH) uniform sampler2D early_depth;
#endif

float source(uvec2 p) {
    if (pc.source.w == 0u) return pyramid[pc.source.z + p.y * pc.source.x + p.x];
#ifdef MULTISAMPLED
    float m = 1.0;
    for (int s = 0; s < int(pc.source.w); ++s) m = min(m, texelFetch(early_depth, ivec2(p), s).r);
    return m;
#else
    return texelFetch(early_depth, ivec2(p), 0).r;
#endif
}

void main() {
    uvec2 t = gl_GlobalInvocationID.xy;
    if (t.x >= pc.target.x || t.y >= pc.target.y) return;
    uvec2 p0 = t * 2u;
    uvec2 p1 = min(p0 + 1u, pc.source.xy - 1u);
    float m = min(min(source(p0), source(uvec2(p1.x, p0.y))), min(source(uvec2(p0.x, p1.y)), source(p1)));
    pyramid[pc.target.z + t.y * pc.target.x + t.x] = m;
}

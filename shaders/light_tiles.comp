#version 450
#extension GL_GOOGLE_include_directive : require
#define CLUSTER_WRITER 1
#include "common.glsl"

// Clustered lights, second pass: one workgroup per screen tile writes the tile's bit mask over
// the bounded lights (bit i: light i's bounding sphere touches the tile's frustum), one mask word
// (32 lights) per invocation at a time. The frustum's four side planes come from the tile's
// corners at two depths, so orthographic views (parallel planes) need nothing apart.
layout(local_size_x = CLUSTER_GROUP) in;
layout(std430, set = SET_FRAME, binding = BINDING_CLUSTERS) buffer Clusters { uint cluster_data[]; };

// The view-space point on the ray through NDC (x, y) at view depth `depth` (distance along -Z).
vec3 at_depth(vec2 ndc, float depth) {
    vec4 p = g.inverse_projection * vec4(ndc, 0.5, 1.0);
    p.xyz /= p.w;
    if (g.projection[3][3] == 1.0) {   // orthographic: parallel rays
        return vec3(p.xy, -depth);
    }
    return p.xyz * (depth / -p.z);
}

// The plane through the side of the tile from NDC corner a to b, facing `inside`.
vec4 side(vec2 a, vec2 b, vec3 inside) {
    vec3 a0 = at_depth(a, 1.0), a1 = at_depth(a, 2.0), b0 = at_depth(b, 1.0);
    vec3 n = normalize(cross(a1 - a0, b0 - a0));
    float d = -dot(n, a0);
    return dot(n, inside) + d < 0.0 ? -vec4(n, d) : vec4(n, d);
}

void main() {
    uint tx = gl_WorkGroupID.x;   // dispatched as tiles across x tiles down
    uint ty = gl_WorkGroupID.y;
    uint tile = ty * g.light_tiles.x + tx;
    bool perspective = g.projection[3][3] != 1.0;
    vec2 viewport = g.bin_depth.zw;
    float px = float(g.light_tiles.w);
    vec2 lo = vec2(tx, ty) * px / viewport * 2.0 - 1.0;
    vec2 hi = min(vec2(tx + 1u, ty + 1u) * px / viewport, vec2(1.0)) * 2.0 - 1.0;
    vec3 inside = at_depth((lo + hi) * 0.5, 1.5);
    vec4 planes[4] = vec4[4](
        side(lo, vec2(lo.x, hi.y), inside),
        side(vec2(hi.x, lo.y), hi, inside),
        side(lo, vec2(hi.x, lo.y), inside),
        side(vec2(lo.x, hi.y), hi, inside));
    uint words = g.light_tiles.z;
    uint out_at = g.light_bins.y + tile * words;
    for (uint w = gl_LocalInvocationIndex; w < words; w += CLUSTER_GROUP) {
        uint bits = 0u;
        uint first = w * 32u;
        uint n = min(32u, g.counts.y - min(first, g.counts.y));
        for (uint j = 0u; j < n; ++j) {
            uint at = g.light_bins.x + 4u * (first + j);
            vec4 s = vec4(uintBitsToFloat(cluster_data[at]), uintBitsToFloat(cluster_data[at + 1u]),
                          uintBitsToFloat(cluster_data[at + 2u]), uintBitsToFloat(cluster_data[at + 3u]));
            // bounded, and (in perspective) not wholly behind the eye; an orthographic near plane
            // may lie behind the camera
            bool touches = s.w > 0.0 && (!perspective || s.z < s.w);
            for (int k = 0; k < 4 && touches; ++k) {
                touches = dot(planes[k].xyz, s.xyz) + planes[k].w >= -s.w;
            }
            bits |= touches ? 1u << j : 0u;
        }
        cluster_data[out_at + w] = bits;
    }
}

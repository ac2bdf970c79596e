#version 450
#extension GL_GOOGLE_include_directive : require
#define CLUSTER_WRITER 1
#include "common.glsl"
#include "light_grid.glsl"

// Clustered lights, first pass: one invocation per light. A bounded point or spot light writes its
// bounding sphere in view space (for light_tiles.comp) and widens the index range of every
// distance bin its sphere reaches; directional and unbounded lights go to the global list every
// fragment loops over. The bins were filled with (0xFFFFFFFF, 0) and the list's count zeroed
// before the dispatch.
layout(local_size_x = CLUSTER_GROUP) in;
layout(std430, set = SET_FRAME, binding = BINDING_CLUSTERS) buffer Clusters { uint cluster_data[]; };

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= g.counts.x) {
        return;
    }
    Light light = lights[i];
    bool bounded = i < g.counts.y && light.position_radius.w > 0.0;
    if (!bounded) {
        uint k = atomicAdd(cluster_data[0], 1u);
        if (k < MAX_GLOBAL_LIGHTS) {
            cluster_data[CLUSTER_GLOBALS + k] = i;
        }
    }
    if (i >= g.counts.y) {
        return;   // directional: no bounds
    }
    uint at = g.light_bins.x + 4u * i;
    if (!bounded) {
        cluster_data[at + 3u] = floatBitsToUint(-1.0);   // in no tile's mask
        return;
    }
    vec4 sphere = light_sphere(light);
    vec3 centre = (g.view * vec4(sphere.xyz, 1.0)).xyz;
    cluster_data[at] = floatBitsToUint(centre.x);
    cluster_data[at + 1u] = floatBitsToUint(centre.y);
    cluster_data[at + 2u] = floatBitsToUint(centre.z);
    cluster_data[at + 3u] = floatBitsToUint(sphere.w);
    float d = length(sphere.xyz - g.eye.xyz);
    uint last = light_bin(d + sphere.w);
    for (uint b = light_bin(d - sphere.w); b <= last; ++b) {
        atomicMin(cluster_data[CLUSTER_HEADER + b], i);
        atomicMax(cluster_data[CLUSTER_HEADER + LIGHT_BINS + b], i);
    }
}

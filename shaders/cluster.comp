#version 450
#extension GL_GOOGLE_include_directive : require
#define CLUSTER_WRITER 1
#include "common.glsl"

// Clustered lights (render/light_clusters.py): one workgroup per view-space cluster (a screen
// tile times an exponential depth slice) lists the bounded point and spot lights whose sphere
// touches the cluster's box; one more workgroup lists the lights every fragment needs
// (directional ones, and point or spot lights without a radius). A cluster's list is gathered in
// shared memory, then copied to a range of the index pool that one atomic reserves. Light indices
// are in no particular order (atomics): the shading sum differs from the loop only by rounding.
layout(local_size_x = CLUSTER_GROUP) in;
layout(std430, set = SET_FRAME, binding = BINDING_CLUSTERS) buffer Clusters { uint cluster_data[]; };

shared uint found;
shared uint start;
shared uint listed[MAX_CLUSTER_LIGHTS];

// The view-space point on the ray through NDC (x, y) at view depth `depth` (distance along -Z).
vec3 at_depth(vec2 ndc, float depth) {
    vec4 p = g.inverse_projection * vec4(ndc, 0.5, 1.0);
    p.xyz /= p.w;
    if (g.projection[3][3] == 1.0) {   // orthographic: parallel rays
        return vec3(p.xy, -depth);
    }
    return p.xyz * (depth / -p.z);
}

void main() {
    uint lid = gl_LocalInvocationIndex;
    uint c = gl_WorkGroupID.x;
    uint total = g.clusters.x * g.clusters.y * g.clusters.z;
    if (lid == 0u) {
        found = 0u;
    }
    barrier();
    if (c == total) {   // the global list
        for (uint i = lid; i < g.counts.x; i += CLUSTER_GROUP) {
            Light light = lights[i];
            if (uint(light.direction_kind.w) == LIGHT_DIRECTIONAL || light.position_radius.w <= 0.0) {
                uint k = atomicAdd(found, 1u);
                if (k < MAX_GLOBAL_LIGHTS) {
                    cluster_data[CLUSTER_GLOBALS + k] = i;
                }
            }
        }
        barrier();
        if (lid == 0u) {
            cluster_data[0] = min(found, uint(MAX_GLOBAL_LIGHTS));
        }
        return;
    }
    uint tx = c % g.clusters.x;
    uint ty = (c / g.clusters.x) % g.clusters.y;
    uint slice = c / (g.clusters.x * g.clusters.y);
    // the tile's corners in NDC (the viewport is tiles * tile size, or less at the far edges)
    vec2 viewport = g.cluster_depth.zw;
    vec2 lo = vec2(tx, ty) * float(g.clusters.w) / viewport * 2.0 - 1.0;
    vec2 hi = min(vec2(tx + 1u, ty + 1u) * float(g.clusters.w) / viewport, vec2(1.0)) * 2.0 - 1.0;
    float s = g.cluster_depth.x;   // the first slice also takes every depth below s
    float d0 = slice == 0u ? 1.0e-6 : s * exp(float(slice) / g.cluster_depth.y);
    float d1 = slice + 1u == g.clusters.z ? 3.0e38 : s * exp(float(slice + 1u) / g.cluster_depth.y);
    vec3 bmin = vec3(3.0e38), bmax = vec3(-3.0e38);
    for (int k = 0; k < 8; ++k) {
        vec2 ndc = vec2((k & 1) == 0 ? lo.x : hi.x, (k & 2) == 0 ? lo.y : hi.y);
        vec3 p = at_depth(ndc, (k & 4) == 0 ? d0 : min(d1, 1.0e18));
        bmin = min(bmin, p);
        bmax = max(bmax, p);
    }
    if (d1 > 1.0e37) {
        bmin.z = -3.0e38;   // the last slice runs to infinity
    }
    for (uint i = lid; i < g.counts.y; i += CLUSTER_GROUP) {
        vec4 pr = lights[i].position_radius;
        if (pr.w <= 0.0) {
            continue;   // unbounded: in the global list
        }
        vec3 centre = (g.view * vec4(pr.xyz, 1.0)).xyz;
        vec3 d = clamp(centre, bmin, bmax) - centre;
        if (dot(d, d) <= pr.w * pr.w) {
            uint k = atomicAdd(found, 1u);
            if (k < MAX_CLUSTER_LIGHTS) {
                listed[k] = i;
            }
        }
    }
    barrier();
    uint n = min(found, uint(MAX_CLUSTER_LIGHTS));
    uint capacity = g.cluster_pool.y;
    uint table = CLUSTER_HEADER + c * CLUSTER_STRIDE;
    if (lid == 0u) {
        uint at = n == 0u ? 0u : atomicAdd(cluster_data[CLUSTER_POOL_USED], n);   // zeroed before the dispatch
        start = at;
        cluster_data[table] = g.cluster_pool.x + at;
        cluster_data[table + 1u] = at >= capacity ? 0u : min(n, capacity - at);   // cut short when the pool is full
        atomicMax(cluster_data[CLUSTER_PEAK], found);
    }
    barrier();
    uint fit = start >= capacity ? 0u : min(n, capacity - start);
    for (uint k = lid; k < fit; k += CLUSTER_GROUP) {
        cluster_data[g.cluster_pool.x + start + k] = listed[k];
    }
}

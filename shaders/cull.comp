#version 450
#extension GL_GOOGLE_include_directive : require
// Indirect mode, pass 1: cull every instance row's bounding sphere against the frustum planes
// (camera-relative, pointing inwards) and append the visible row's index to its key's region.
// The camera's view and each shadow view (render/shadow_indirect.py) run it over the same rows,
// each with its own set 1; a shadow view leaves out the rows tagged NotShadowCaster (pc.skip).
#include "common.glsl"
#define IDS_WRITABLE 1
#include "indirect.glsl"

layout(local_size_x = CULL_GROUP) in;
layout(push_constant) uniform Cull { CullPush pc; };

void main() {
    uint i = pc.first_row + gl_GlobalInvocationID.x;
    if (i >= pc.row_end) return;
    Instance inst = instances[i];
    if ((inst.misc.w & pc.skip) != 0u) return;
    uint key = inst.misc.y;
    vec4 s = keys[key].sphere;
    vec4 c = vec4(s.xyz, 1.0);
    vec3 center = vec3(dot(inst.model[0], c), dot(inst.model[1], c), dot(inst.model[2], c));
    vec3 c0 = vec3(inst.model[0].x, inst.model[1].x, inst.model[2].x);
    vec3 c1 = vec3(inst.model[0].y, inst.model[1].y, inst.model[2].y);
    vec3 c2 = vec3(inst.model[0].z, inst.model[1].z, inst.model[2].z);
    float r = s.w * sqrt(max(dot(c0, c0), max(dot(c1, c1), dot(c2, c2))));
    for (uint p = 0; p < pc.plane_count; ++p) {
        if (dot(pc.planes[p].xyz, center) + pc.planes[p].w < -r) return;
    }
    uint slot = atomicAdd(visible[key], 1u);
    ids_out[keys[key].base + slot] = i;
}

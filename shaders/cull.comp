#version 450
#extension GL_GOOGLE_include_directive : require
// Indirect mode, pass 1: cull every instance row's bounding sphere against the frustum planes
// (camera-relative, pointing inwards) and append the visible row's index to its key's region.
// The camera's view and each shadow view (render/shadow_indirect.py) run it over the same rows,
// each with its own set 1; a shadow view leaves out the rows tagged NotShadowCaster (pc.skip).
// With occlusion culling the camera's view takes cull_early.comp and cull_late.comp instead.
#include "common.glsl"
#define IDS_WRITABLE 1
#include "indirect.glsl"

layout(local_size_x = CULL_GROUP) in;
layout(push_constant) uniform Cull { CullPush pc; };

#include "cull_row.glsl"

void main() {
    uint i = pc.first_row + gl_GlobalInvocationID.x;
    if (i >= pc.row_end) return;
    Instance inst = instances[i];
    if ((inst.misc.w & pc.skip) != 0u) return;
    vec3 center;
    float radius;
    row_sphere(inst, center, radius);
    if (in_frustum(center, radius)) append_row(i, inst.misc.y, center, radius);
}

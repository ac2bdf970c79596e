#version 450
#extension GL_GOOGLE_include_directive : require
// Occlusion culling, early pass (render/occlusion.py): the rows the last frame found visible,
// still in the frustum, whose material hides what is behind it on every covered pixel (opaque,
// one-sided); their depth alone is drawn, then reduced to the pyramid cull_late.comp reads.
#include "common.glsl"
#define IDS_WRITABLE 1
#include "indirect.glsl"

layout(local_size_x = CULL_GROUP) in;
layout(push_constant) uniform Cull { CullPush pc; };

#include "cull_row.glsl"
#include "occlusion.glsl"

void main() {
    uint i = pc.first_row + gl_GlobalInvocationID.x;
    if (i >= pc.row_end || row_visible[i] == 0u) return;
    Instance inst = instances[i];
    uvec4 kind = materials[inst.misc.x].kind;
    if (kind.y != ALPHA_OPAQUE || kind.z != 0u) return;
    vec3 center;
    float radius;
    row_sphere(inst, center, radius);
    if (in_frustum(center, radius)) append_row(i, inst.misc.y, center, radius);
}

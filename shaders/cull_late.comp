#version 450
#extension GL_GOOGLE_include_directive : require
// Occlusion culling, late pass (render/occlusion.py): every row against the frustum, then its
// sphere's screen rect against the depth pyramid of the early pass. Whatever is visible in the
// final image is in front of the early depth somewhere it covers (the early rows are drawn again
// here), so it passes: the image is the one frustum culling alone gives. The verdict is kept
// for the next frame's early pass.
#include "common.glsl"
#define IDS_WRITABLE 1
#include "indirect.glsl"

layout(local_size_x = CULL_GROUP) in;
layout(push_constant) uniform Cull { CullPush pc; };

#include "cull_row.glsl"
#define VISIBILITY_WRITABLE 1
#include "occlusion.glsl"

void main() {
    uint i = pc.first_row + gl_GlobalInvocationID.x;
    if (i >= pc.row_end) return;
    Instance inst = instances[i];
    vec3 center;
    float radius;
    row_sphere(inst, center, radius);
    bool visible = in_frustum(center, radius) && occlusion_visible(center, radius);
    row_visible[i] = visible ? 1u : 0u;
    if (visible) append_row(i, inst.misc.y, center, radius);
}

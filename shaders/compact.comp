#version 450
#extension GL_GOOGLE_include_directive : require
// Indirect mode, pass 2: one instanced draw command per non-empty key, appended to its
// winding's list; state.draw_counts[] is the count vkCmdDrawIndexedIndirectCount reads.
#include "common.glsl"
#include "indirect.glsl"

layout(std430, set = SET_INDIRECT, binding = BINDING_COMMANDS) writeonly buffer Commands { DrawCommand commands[]; };

layout(local_size_x = COMPACT_GROUP) in;
layout(push_constant) uniform Compact { CompactPush pc; };

void main() {
    uint key = gl_GlobalInvocationID.x;
    if (key >= pc.key_count) return;
    uint n = visible[key];
    if (n == 0u) return;
    uint winding = key & 1u;
    uint d = atomicAdd(state.draw_counts[winding], 1u);
    KeyInfo k = keys[key];
    // gl_InstanceIndex = first_instance + i: the vertex shader reads ids[gl_InstanceIndex]
    commands[winding * pc.mesh_count + d] = DrawCommand(k.index_count, n, k.first_index, k.vertex_offset, k.base);
}

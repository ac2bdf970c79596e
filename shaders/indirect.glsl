// The indirect mode's buffers (set 0, after common.glsl's bindings 0-3). A key is
// mesh * 2 + mirrored (negative determinant: drawn with the opposite front face); the CPU writes
// it into each instance row's misc.y. cull.comp gives every visible row a slot in its key's
// region of `ids`; compact.comp turns the non-empty keys into draw commands, one list per winding.
struct KeyInfo {
    uint index_count;
    uint first_index;   // of the mesh in the merged index buffer
    int vertex_offset;  // of the mesh in the merged vertex buffer
    uint base;          // first slot of this key's region of `ids`
    vec4 sphere;        // the mesh's bounding sphere: centre xyz, radius
};
#ifdef IDS_WRITABLE
layout(std430, set = 0, binding = 4) writeonly buffer VisibleIds { uint ids_out[]; };
#else
layout(std430, set = 0, binding = 4) readonly buffer VisibleIds { uint ids[]; };
#endif
layout(std430, set = 0, binding = 5) readonly buffer Keys { KeyInfo keys[]; };
layout(std430, set = 0, binding = 6) buffer DrawState {
    uint draw_counts[2];    // commands per winding (the count buffer of vkCmdDrawIndexedIndirectCount)
    uint state_pad[2];
    uint visible[];         // visible rows per key
};

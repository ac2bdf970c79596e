// The indirect path's set (1). A key is mesh * 2 + mirrored (negative determinant: drawn with
// the opposite front face); the CPU writes it into each instance row's misc.y. cull.comp gives
// every visible row a slot in its key's region of `ids`; compact.comp turns the non-empty keys
// into draw commands, one list per winding.
#ifdef IDS_WRITABLE
layout(std430, set = SET_INDIRECT, binding = BINDING_IDS) writeonly buffer VisibleIds { uint ids_out[]; };
#else
layout(std430, set = SET_INDIRECT, binding = BINDING_IDS) readonly buffer VisibleIds { uint ids[]; };
#endif
layout(std430, set = SET_INDIRECT, binding = BINDING_KEYS) readonly buffer Keys { KeyInfo keys[]; };
layout(std430, set = SET_INDIRECT, binding = BINDING_DRAW_STATE) buffer DrawState {
    DrawStateHeader state;
    uint visible[];         // visible rows per key
};

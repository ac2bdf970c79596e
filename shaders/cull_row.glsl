// One instance row's bounding sphere and its frustum test, shared by cull.comp (one pass: the
// camera without occlusion culling, and the shadow views), cull_early.comp and cull_late.comp
// (two-phase occlusion culling, render/occlusion.py). Needs common.glsl, indirect.glsl and a
// push block `pc` of type CullPush.

// The row's sphere in the render-relative world: the key's mesh sphere through the model matrix,
// its radius scaled by the largest column.
void row_sphere(Instance inst, out vec3 center, out float radius) {
    vec4 s = keys[inst.misc.y].sphere;
    vec4 c = vec4(s.xyz, 1.0);
    center = vec3(dot(inst.model[0], c), dot(inst.model[1], c), dot(inst.model[2], c));
    vec3 c0 = vec3(inst.model[0].x, inst.model[1].x, inst.model[2].x);
    vec3 c1 = vec3(inst.model[0].y, inst.model[1].y, inst.model[2].y);
    vec3 c2 = vec3(inst.model[0].z, inst.model[1].z, inst.model[2].z);
    radius = s.w * sqrt(max(dot(c0, c0), max(dot(c1, c1), dot(c2, c2))));
}

// Against the planes (camera-relative, pointing inwards): false when wholly outside one.
bool in_frustum(vec3 center, float radius) {
    for (uint p = 0; p < pc.plane_count; ++p) {
        if (dot(pc.planes[p].xyz, center) + pc.planes[p].w < -radius) return false;
    }
    return true;
}

// The row drawn: a slot in its key's region of ids.
void append_row(uint i, uint key) {
    uint slot = atomicAdd(visible[key], 1u);
    ids_out[keys[key].base + slot] = i;
}

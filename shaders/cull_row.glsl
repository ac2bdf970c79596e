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

// A level of detail's error may cover this many pixels (mesh_lod.py lod_for_screen_size's
// threshold_px).
const float LOD_PIXELS = 1.0;

// The level of detail the row is drawn at (0: its mesh): with CULL_LOD, the coarsest level of
// its mesh whose error, projected at the sphere's nearest point (the camera's globals g), covers
// at most LOD_PIXELS; else 0. The same rule as mesh_lod.py lod_for_screen_size.
uint draw_level(uint key, vec3 center, float radius) {
    KeyInfo k = keys[key];
    if ((pc.occlusion.w & CULL_LOD) == 0u || k.lod.y == 0u) return 0u;
    mat4 P = g.projection;
    float focal = 0.5 * float(pc.occlusion.y) * abs(P[1][1]);  // pixels a unit covers at distance 1
    float nearest = P[2][3] != 0.0 ? length(center - g.eye.xyz) - radius : 1.0;
    float scale = radius / k.sphere.w;
    uint level = 0u;
    for (uint l = 0u; l < min(k.lod.y, uint(MAX_LODS)); ++l) {
        if (k.lod_error[l] * scale * focal <= LOD_PIXELS * nearest) level = l + 1u;
    }
    return level;
}

// The row drawn: a slot in the region of the key of the level it is drawn at, holding its index
// and, above ROW_LEVEL_SHIFT, that level (a skinned or morphed row's vertex shader reads the
// weights and deltas of the level it draws: instance_row.glsl).
void append_row(uint i, uint key, vec3 center, float radius) {
    uint level = draw_level(key, center, radius);
    uint drawn = level == 0u ? key : (keys[key].lod.x + level - 1u) * 2u + (key & 1u);
    uint slot = atomicAdd(visible[drawn], 1u);
    ids_out[keys[drawn].base + slot] = i | (level << uint(ROW_LEVEL_SHIFT));
}

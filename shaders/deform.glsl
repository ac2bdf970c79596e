// A deformed row's vertex, by its index `v` in its own mesh: the vertex shaders'
// (instance_row.glsl: gl_VertexIndex - gl_BaseVertex) and posed_vertices.comp's (one invocation
// a vertex), so that what the GPU draws and what it reads back are posed by the same code.
// Needs the frame set's Instance (common.glsl).

// Skinning (render/extract/skins.py, render/assets/skin_vertices.py): a row whose misc.w >> 1 is
// not 0 is a skinned mesh's, its joint matrices starting at (misc.w >> 1) - 1; its vertex's
// eight joints and weights are found by the vertex's index in its mesh, or in the level of
// detail `level` of it (0: the mesh itself) the indirect mode draws. Its model rows (which place only its bounds, for
// culling) give way to the weighted sum of those joints' matrices, so the normal matrix and the
// position below follow the pose as a model matrix would.
// The mesh pipelines' specialisation constant (their fragment shaders' too): without
// FEATURE_DEFORM no row is deformed, and the code below is compiled out (its registers slow
// every vertex). Pipelines made without the constant (posed_vertices.comp) keep it.
layout(constant_id = 0) const uint MATERIAL_FEATURES = 0xFFFFFFFFu;
const bool DEFORM = (MATERIAL_FEATURES & uint(FEATURE_DEFORM)) != 0u;

layout(std430, set = SET_FRAME, binding = BINDING_JOINTS) readonly buffer Joints { vec4 joint_rows[]; };
layout(std430, set = SET_FRAME, binding = BINDING_SKIN_VERTICES) readonly buffer SkinVertices { uint skin_words[]; };

// Where the header (skin_vertices.py) says the row's mesh's (at `level`) skin records (part 0) or
// morph block (part 1) start; 0xFFFFFFFF for none.
uint deform_data(Instance inst, uint level, uint part) {
    uint mesh = inst.misc.y >> 1;
    if (mesh >= skin_words[0] || level > uint(MAX_LODS)) return 0xFFFFFFFFu;
    return skin_words[1u + uint(SKIN_HEADER_WORDS) * mesh + 2u * level + part];
}

Instance skin_vertex(Instance inst, uint v, uint level) {
    uint first = inst.misc.w >> 1;
    if (!DEFORM || first == 0u) return inst;
    uint records = deform_data(inst, level, 0u);
    if (records == 0xFFFFFFFFu) return inst;
    uint at = records + v * uint(SKIN_WORDS);
    vec4 r0 = vec4(0.0), r1 = vec4(0.0), r2 = vec4(0.0);
    for (uint k = 0u; k < 8u; ++k) {
        float w = uintBitsToFloat(skin_words[at + 4u + k]);
        if (w == 0.0) continue;
        uint pair = skin_words[at + k / 2u];
        uint joint = (k & 1u) == 0u ? (pair & 0xFFFFu) : (pair >> 16);
        uint row = 3u * (first - 1u + joint);
        r0 += w * joint_rows[row];
        r1 += w * joint_rows[row + 1u];
        r2 += w * joint_rows[row + 2u];
    }
    inst.model[0] = r0;
    inst.model[1] = r1;
    inst.model[2] = r2;
    return inst;
}

// Morph targets: a row whose misc.z >> 1 is not 0 has its eight weights in joint_rows at
// (misc.z >> 1) - 1 and the row after; its mesh's morph block (skin_vertices.py) holds each
// target's deltas by vertex. The vertex moves by the weighted sum of its deltas (before a skin,
// as glTF orders them).
void morph_vertex(Instance inst, uint v, uint level, inout vec3 position, inout vec3 normal, inout vec3 tangent) {
    uint at = inst.misc.z >> 1;
    if (!DEFORM || at == 0u) return;
    uint block = deform_data(inst, level, 1u);
    if (block == 0xFFFFFFFFu) return;
    uint targets = skin_words[block], vertices = skin_words[block + 1u];
    vec4 lo = joint_rows[at - 1u], hi = joint_rows[at];
    float w[8] = float[8](lo.x, lo.y, lo.z, lo.w, hi.x, hi.y, hi.z, hi.w);
    for (uint t = 0u; t < min(targets, 8u); ++t) {
        if (w[t] == 0.0) continue;
        uint r = block + 2u + (t * vertices + v) * uint(MORPH_WORDS);
        position += w[t] * vec3(uintBitsToFloat(skin_words[r]), uintBitsToFloat(skin_words[r + 1u]),
                                uintBitsToFloat(skin_words[r + 2u]));
        normal += w[t] * vec3(uintBitsToFloat(skin_words[r + 3u]), uintBitsToFloat(skin_words[r + 4u]),
                              uintBitsToFloat(skin_words[r + 5u]));
        tangent += w[t] * vec3(uintBitsToFloat(skin_words[r + 6u]), uintBitsToFloat(skin_words[r + 7u]),
                               uintBitsToFloat(skin_words[r + 8u]));
    }
}

// A model-space position in the render-relative world: the row's 3x4 model matrix.
vec3 instance_world(Instance inst, vec3 position) {
    vec4 p = vec4(position, 1.0);
    return vec3(dot(inst.model[0], p), dot(inst.model[1], p), dot(inst.model[2], p));
}

// The normal matrix (mesh_vertex.glsl's, posed_vertices.comp's): the cofactor of the model's
// 3x3 part (det * inverse transpose), made from columns scaled by the largest one (so huge scales do not overflow and tiny ones do not all
// vanish), its sign flipped for mirrored matrices. Finite for zero scales too: a flattened axis
// gives a zero term and the fragment shader falls back to the face normal. The same formula as
// maths.transform.normal_scale, per vertex instead of per entity on the CPU.
mat3 normal_matrix(Instance inst) {
    vec3 c0 = vec3(inst.model[0].x, inst.model[1].x, inst.model[2].x);
    vec3 c1 = vec3(inst.model[0].y, inst.model[1].y, inst.model[2].y);
    vec3 c2 = vec3(inst.model[0].z, inst.model[1].z, inst.model[2].z);
    vec3 top = max(max(abs(c0), abs(c1)), abs(c2));
    float peak = max(max(top.x, top.y), top.z);
    if (peak > 0.0) {
        float s = 1.0 / peak;
        c0 *= s; c1 *= s; c2 *= s;
    }
    vec3 x = cross(c1, c2), y = cross(c2, c0), z = cross(c0, c1);
    float sign_det = dot(c0, x) < 0.0 ? -1.0 : 1.0;
    return mat3(x, y, z) * sign_det;
}

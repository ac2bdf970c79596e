// The mesh vertex shader body, shared by mesh.vert (instance rows from a storage buffer, one
// instanced draw per mesh run), mesh_push.vert (the row in push constants, one draw per
// entity: the seed's way) and mesh_indirect.vert (the row index from the ids cull.comp wrote).
// With TEXTURED defined (the *_textured.vert variants) it also passes texture coordinates and the
// tangent frame on; only the variants read them, so only they bind those attributes.
layout(location = 0) in vec3 in_position;
layout(location = 1) in vec3 in_normal;

layout(location = 0) out vec3 v_position;
layout(location = 1) out vec3 v_normal;
layout(location = 2) flat out uint v_material;
#ifdef TEXTURED
layout(location = 2) in vec2 in_uv;
layout(location = 3) in vec4 in_tangent;
layout(location = 3) out vec2 v_uv;
layout(location = 4) out vec4 v_tangent;
#endif

#include "instance_row.glsl"

void main() {
    Instance inst = instance_row();
    vec3 position = in_position, normal = in_normal, tangent = vec3(0.0);
#ifdef TEXTURED
    tangent = in_tangent.xyz;
#endif
    morphed(inst, position, normal, tangent);
    vec3 world = instance_world(inst, position);
    v_position = world;
    mat3 nm = normal_matrix(inst);
    v_normal = nm * normal;
    v_material = inst.misc.x | ((inst.misc.z & 1u) << 31);   // bit 31: NotShadowReceiver
#ifdef TEXTURED
    // tangents move with the surface (the model matrix); the bitangent's sign flips with mirroring
    vec3 t = vec3(dot(inst.model[0].xyz, tangent), dot(inst.model[1].xyz, tangent), dot(inst.model[2].xyz, tangent));
    float mirrored = determinant(mat3(inst.model[0].xyz, inst.model[1].xyz, inst.model[2].xyz)) < 0.0 ? -1.0 : 1.0;
    v_uv = in_uv;
    v_tangent = vec4(t, in_tangent.w * mirrored);
#endif
    gl_Position = g.projection * (g.view * vec4(world, 1.0));
    gl_PointSize = 1.0;  // --fill points draws the vertices: one pixel each
}

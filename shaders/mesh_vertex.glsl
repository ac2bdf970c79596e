// The mesh vertex shader body, shared by mesh.vert (instance rows from a storage buffer, one
// instanced draw per mesh run), mesh_push.vert (the row in push constants, one draw per
// entity: the seed's way) and mesh_indirect.vert (the row index from the ids cull.comp wrote).
layout(location = 0) in vec3 in_position;
layout(location = 1) in vec3 in_normal;

layout(location = 0) out vec3 v_position;
layout(location = 1) out vec3 v_normal;
layout(location = 2) flat out uint v_material;

#ifdef PUSH_INSTANCE
layout(push_constant) uniform Push { Instance row; } push;
#endif

void main() {
#if defined(PUSH_INSTANCE)
    Instance inst = push.row;
#elif defined(INDIRECT_INSTANCE)
    Instance inst = instances[ids[gl_InstanceIndex]];
#else
    Instance inst = instances[gl_InstanceIndex];
#endif
    vec4 p = vec4(in_position, 1.0);
    vec3 world = vec3(dot(inst.m0, p), dot(inst.m1, p), dot(inst.m2, p));
    v_position = world;
    v_normal = vec3(dot(inst.n0.xyz, in_normal), dot(inst.n1.xyz, in_normal), dot(inst.n2.xyz, in_normal));
    v_material = inst.misc.x;
    gl_Position = g.projection * (g.view * vec4(world, 1.0));
}

// The shadow passes' vertex shader body (render/shadow_pass.py): the position alone, through the
// shadow view's globals (its own set 0: g.projection and g.view are the light's). shadow.vert
// reads the row from the instance buffer, shadow_push.vert from push constants (per_entity),
// shadow_indirect.vert through the view's ids, culled on the GPU (render/shadow_indirect.py:
// instances[ids[gl_InstanceIndex]], as mesh_indirect.vert); the _cutout variants also pass
// texture coordinates and the material on.
layout(location = 0) in vec3 in_position;
#ifdef CUTOUT
// alpha-masked materials cut holes in the map (shadow_cutout.frag): the texture coordinates and
// the material go on
layout(location = 1) in vec2 in_uv;
layout(location = 0) out vec2 v_uv;
layout(location = 1) flat out uint v_material;
#endif

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
    vec3 world = vec3(dot(inst.model[0], p), dot(inst.model[1], p), dot(inst.model[2], p));
    gl_Position = g.projection * (g.view * vec4(world, 1.0));
#ifdef CUTOUT
    v_uv = in_uv;
    v_material = inst.misc.x;
#endif
}

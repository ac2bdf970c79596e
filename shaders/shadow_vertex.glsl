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

#include "instance_row.glsl"

void main() {
    Instance inst = instance_row();
    vec3 position = in_position, normal = vec3(0.0), tangent = vec3(0.0);
    morphed(inst, position, normal, tangent);
    vec3 world = instance_world(inst, position);
    gl_Position = g.projection * (g.view * vec4(world, 1.0));
#ifdef CUTOUT
    v_uv = in_uv;
    v_material = inst.misc.x;
#endif
}

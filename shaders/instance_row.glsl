// This vertex's instance row, however the path hands it over (mesh_vertex.glsl and
// shadow_vertex.glsl): from push constants (PUSH_INSTANCE: per_entity), through the ids cull.comp
// wrote (INDIRECT_INSTANCE: the indirect mode), or from the instance buffer by instance index.
#ifdef PUSH_INSTANCE
layout(push_constant) uniform Push { Instance row; } push;
#endif

Instance instance_row() {
#if defined(PUSH_INSTANCE)
    return push.row;
#elif defined(INDIRECT_INSTANCE)
    return instances[ids[gl_InstanceIndex]];
#else
    return instances[gl_InstanceIndex];
#endif
}

// A model-space position in the render-relative world: the row's 3x4 model matrix.
vec3 instance_world(Instance inst, vec3 position) {
    vec4 p = vec4(position, 1.0);
    return vec3(dot(inst.model[0], p), dot(inst.model[1], p), dot(inst.model[2], p));
}

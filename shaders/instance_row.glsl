// This vertex's instance row, however the path hands it over (mesh_vertex.glsl and
// shadow_vertex.glsl): from push constants (PUSH_INSTANCE: per_entity), through the ids cull.comp
// wrote (INDIRECT_INSTANCE: the indirect mode), or from the instance buffer by instance index.
#ifdef PUSH_INSTANCE
layout(push_constant) uniform Push { Instance row; } push;
#endif

#include "deform.glsl"

// The vertex's index in its own mesh or level (the indirect mode draws from the merged buffer).
uint mesh_vertex_index() { return uint(gl_VertexIndex - gl_BaseVertexARB); }

// The level of detail drawn (0: the mesh itself): the indirect mode's cull passes put it above
// ROW_LEVEL_SHIFT in the row's entry of ids (cull_row.glsl); the other paths draw the mesh.
uint row_level = 0u;

Instance skinned(Instance inst) { return skin_vertex(inst, mesh_vertex_index(), row_level); }

void morphed(Instance inst, inout vec3 position, inout vec3 normal, inout vec3 tangent) {
    morph_vertex(inst, mesh_vertex_index(), row_level, position, normal, tangent);
}

Instance instance_row() {
#if defined(PUSH_INSTANCE)
    return skinned(push.row);
#elif defined(INDIRECT_INSTANCE)
    uint entry = ids[gl_InstanceIndex];
    row_level = entry >> uint(ROW_LEVEL_SHIFT);
    return skinned(instances[entry & ((1u << uint(ROW_LEVEL_SHIFT)) - 1u)]);
#else
    return skinned(instances[gl_InstanceIndex]);
#endif
}

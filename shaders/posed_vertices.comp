#version 450
#extension GL_GOOGLE_include_directive : require
// A deformed instance row's vertices as the vertex shaders pose them (render/draw/posed_vertices.py):
// one invocation a vertex of the row's mesh runs deform.glsl's skin and morph functions, the
// vertex shaders' own, and writes the render-relative position and the normal (the normal
// matrix's, not normalised) as two vec4 rows.
#include "common.glsl"
#include "deform.glsl"

layout(local_size_x = POSED_GROUP) in;
// the mesh's vertex buffer (MESH_VERTEX, MESH_VERTEX_FLOATS floats a vertex) and the output
layout(std430, set = 1, binding = 0) readonly buffer Rest { float rest[]; };
layout(std430, set = 1, binding = 1) writeonly buffer Posed { vec4 posed[]; };
layout(push_constant) uniform Probe { uint row; uint vertices; uint first; } pc;

void main() {
    uint v = gl_GlobalInvocationID.x;
    if (v >= pc.vertices) return;
    Instance inst = skin_vertex(instances[pc.row], v);
    uint at = v * uint(MESH_VERTEX_FLOATS);
    vec3 position = vec3(rest[at], rest[at + 1u], rest[at + 2u]);
    vec3 normal = vec3(rest[at + 3u], rest[at + 4u], rest[at + 5u]);
    uint t = at + uint(MESH_VERTEX_UV) + 2u;
    vec3 tangent = vec3(rest[t], rest[t + 1u], rest[t + 2u]);
    morph_vertex(inst, v, position, normal, tangent);
    uint out_at = 2u * (pc.first + v);
    posed[out_at] = vec4(instance_world(inst, position), 1.0);
    posed[out_at + 1u] = vec4(normal_matrix(inst) * normal, 0.0);
}

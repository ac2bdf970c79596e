#version 450
#extension GL_GOOGLE_include_directive : require
// A deformed instance row's vertices as the vertex shaders pose them (render/draw/posed_vertices.py):
// one invocation a vertex of the row's mesh runs deform.glsl's skin and morph functions, the
// vertex shaders' own, and writes the render-relative position, and with `normals` the normal
// (the normal matrix's, not normalised) after it. The row comes in the push constants: a row
// the camera culled is in no instance buffer, and the ray-traced shadows still need it.
#include "common.glsl"
#include "deform.glsl"

layout(local_size_x = POSED_GROUP) in;
// the mesh's vertex buffer (MESH_VERTEX: MESH_VERTEX_FLOATS floats a vertex) and the output
layout(std430, set = 1, binding = 0) readonly buffer Rest { float rest[]; };
layout(std430, set = 1, binding = 1) writeonly buffer Posed { vec4 posed[]; };
layout(push_constant) uniform Probe { Instance row; uint vertices; uint first; uint normals; } pc;

void main() {
    uint v = gl_GlobalInvocationID.x;
    if (v >= pc.vertices) return;
    Instance inst = skin_vertex(pc.row, v, 0u);
    uint at = v * uint(MESH_VERTEX_FLOATS);
    vec3 position = vec3(rest[at], rest[at + 1u], rest[at + 2u]);
    vec3 normal = vec3(rest[at + 3u], rest[at + 4u], rest[at + 5u]);
    uint t = at + uint(MESH_VERTEX_UV) + 2u;
    vec3 tangent = vec3(rest[t], rest[t + 1u], rest[t + 2u]);
    morph_vertex(inst, v, 0u, position, normal, tangent);
    vec4 world = vec4(instance_world(inst, position), 1.0);
    if (pc.normals == 0u) {
        posed[pc.first + v] = world;  // a bottom level's vertices (render/raytracing/deformed.py)
        return;
    }
    posed[2u * (pc.first + v)] = world;
    posed[2u * (pc.first + v) + 1u] = vec4(normal_matrix(inst) * normal, 0.0);
}

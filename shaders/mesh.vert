#version 450
#extension GL_GOOGLE_include_directive : require
#include "common.glsl"

layout(location = 0) in vec3 in_position;
layout(location = 1) in vec3 in_normal;

layout(location = 0) out vec3 v_position;
layout(location = 1) out vec3 v_normal;
layout(location = 2) flat out uint v_material;

void main() {
    Instance inst = instances[gl_InstanceIndex];
    vec4 p = vec4(in_position, 1.0);
    vec3 world = vec3(dot(inst.m0, p), dot(inst.m1, p), dot(inst.m2, p));
    v_position = world;
    v_normal = vec3(dot(inst.n0.xyz, in_normal), dot(inst.n1.xyz, in_normal), dot(inst.n2.xyz, in_normal));
    v_material = inst.misc.x;
    gl_Position = g.projection * (g.view * vec4(world, 1.0));
}

#version 450
#extension GL_GOOGLE_include_directive : require
#extension GL_ARB_shader_draw_parameters : require  // gl_BaseVertexARB (instance_row.glsl)
#define INDIRECT_INSTANCE 1
#include "common.glsl"
#include "indirect.glsl"
#include "mesh_vertex.glsl"

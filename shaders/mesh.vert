#version 450
#extension GL_GOOGLE_include_directive : require
#extension GL_ARB_shader_draw_parameters : require  // gl_BaseVertexARB (instance_row.glsl)
#include "common.glsl"
#include "mesh_vertex.glsl"

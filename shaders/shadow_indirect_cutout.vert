#version 450
#extension GL_GOOGLE_include_directive : require
#extension GL_ARB_shader_draw_parameters : require  // gl_BaseVertexARB (instance_row.glsl)
#define CUTOUT 1
#define INDIRECT_INSTANCE 1
#include "common.glsl"
#include "indirect.glsl"
#include "shadow_vertex.glsl"

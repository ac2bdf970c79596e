#version 450
#extension GL_GOOGLE_include_directive : require
#extension GL_KHR_shader_subgroup_arithmetic : require
// weighted blended transparency (render/oit_pass.py): the blended rows' accumulation
#define TEXTURED 1
#define CLUSTERED 1
#define OIT 1
#include "common.glsl"
#include "shading.glsl"
#include "mesh_fragment.glsl"

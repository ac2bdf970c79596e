#version 450
#extension GL_GOOGLE_include_directive : require
#extension GL_KHR_shader_subgroup_arithmetic : require
#define TEXTURED 1
#define CLUSTERED 1
#include "common.glsl"
#include "shading.glsl"
#include "mesh_fragment.glsl"

#version 450
#extension GL_GOOGLE_include_directive : require
// the clustered lights' walk is shared by a subgroup (subgroupMin/Max/Or): a variant of its own,
// so devices without subgroup arithmetic in fragment shaders still run the plain one
#extension GL_KHR_shader_subgroup_arithmetic : require
#define CLUSTERED 1
#include "common.glsl"
#include "shading.glsl"
#include "mesh_fragment.glsl"

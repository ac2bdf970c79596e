#version 450
#extension GL_GOOGLE_include_directive : require
// weighted blended transparency (render/oit_pass.py): the blended rows' accumulation
#define OIT 1
#include "common.glsl"
#include "shading.glsl"
#include "mesh_fragment.glsl"

#version 450
#extension GL_GOOGLE_include_directive : require
#define CUTOUT 1
#include "common.glsl"
#include "shadow_vertex.glsl"

#version 450
#extension GL_GOOGLE_include_directive : require
#include "common.glsl"
#include "shadow_vertex.glsl"

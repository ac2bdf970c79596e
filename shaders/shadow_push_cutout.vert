#version 450
#extension GL_GOOGLE_include_directive : require
#define PUSH_INSTANCE 1
#define CUTOUT 1
#include "common.glsl"
#include "shadow_vertex.glsl"

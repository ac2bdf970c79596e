#version 450
#extension GL_GOOGLE_include_directive : require
#define INDIRECT_INSTANCE 1
#include "common.glsl"
#include "indirect.glsl"
#include "shadow_vertex.glsl"

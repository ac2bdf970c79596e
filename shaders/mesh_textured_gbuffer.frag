#version 450
#extension GL_GOOGLE_include_directive : require
#define TEXTURED 1
#define GBUFFER 1
#include "common.glsl"
#include "shading.glsl"
#include "mesh_fragment.glsl"

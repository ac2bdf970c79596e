#version 450
#extension GL_GOOGLE_include_directive : require
#define TEXTURED 1
#define PUSH_INSTANCE 1
#include "common.glsl"
#include "mesh_vertex.glsl"

#version 450
#extension GL_GOOGLE_include_directive : require
// the deferred form's G-buffer pass (gpu/gbuffer.py): no lights here, render/deferred_pass.py adds them
#define GBUFFER 1
#include "common.glsl"
#include "shading.glsl"
#include "mesh_fragment.glsl"

#version 450
#extension GL_GOOGLE_include_directive : require
// depth_reduce.comp for an early depth image with MSAA samples (render/occlusion.py).
#define MULTISAMPLED 1
#include "depth_reduce.glsl"

#version 450
#extension GL_GOOGLE_include_directive : require
// depth_reduce.comp for a single-sample early depth image (render/occlusion.py).
#include "depth_reduce.glsl"

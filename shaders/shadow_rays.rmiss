#version 460
// shadow_rays.rgen's miss: nothing between the surface and the light.
#extension GL_EXT_ray_tracing : require

layout(location = 0) rayPayloadInEXT float lit;

void main() {
    lit = 1.0;
}

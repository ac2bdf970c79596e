#version 460
// ray_cast.rgen's miss: no hit.
#extension GL_EXT_ray_tracing : require

layout(location = 0) rayPayloadInEXT vec4 payload;

void main() {
    payload = vec4(-1.0, -1.0, -1.0, -1.0);
}

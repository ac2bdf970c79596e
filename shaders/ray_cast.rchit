#version 460
// ray_cast.rgen's closest hit: distance along the ray, the instance's custom index, the triangle,
// the instance.
#extension GL_EXT_ray_tracing : require

layout(location = 0) rayPayloadInEXT vec4 payload;

void main() {
    payload = vec4(gl_HitTEXT, float(gl_InstanceCustomIndexEXT), float(gl_PrimitiveID), float(gl_InstanceID));
}

#version 450
#extension GL_GOOGLE_include_directive : require
#include "layouts.glsl"
// Dear ImGui's vertices: pixel positions (origin top-left, y down, as Vulkan's clip space),
// texture coordinates, sRGB colour. The targets are sRGB formats that encode on write, so the
// colour is decoded to linear here and comes out as ImGui meant it.
layout(location = 0) in vec2 in_position;
layout(location = 1) in vec2 in_uv;
layout(location = 2) in vec4 in_color;

layout(push_constant) uniform Push { ImGuiPush push; };

layout(location = 0) out vec4 v_color;
layout(location = 1) out vec2 v_uv;

vec3 srgb_to_linear(vec3 c) {
    return mix(c / 12.92, pow((c + 0.055) / 1.055, vec3(2.4)), greaterThan(c, vec3(0.04045)));
}

void main() {
    v_color = vec4(srgb_to_linear(in_color.rgb), in_color.a);
    v_uv = in_uv;
    gl_Position = vec4(in_position * push.scale + push.translate, 0.0, 1.0);
}

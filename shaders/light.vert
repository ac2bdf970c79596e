#version 450
#extension GL_GOOGLE_include_directive : require
#include "common.glsl"

// One camera-facing quad per light (6 vertices made here, no vertex buffer). Lights arrive
// sorted far to near, so alpha blending composes them in the right order.
layout(push_constant) uniform Push { BillboardPush push; };

layout(location = 0) out vec2 v_offset;
layout(location = 1) flat out vec3 v_color;

const vec2 CORNERS[6] = vec2[](vec2(-1.0, -1.0), vec2(1.0, -1.0), vec2(1.0, 1.0),
                               vec2(-1.0, -1.0), vec2(1.0, 1.0), vec2(-1.0, 1.0));

void main() {
    Light l = lights[gl_InstanceIndex];
    v_offset = CORNERS[gl_VertexIndex];
    v_color = l.color_intensity.rgb;
    vec4 center = g.view * vec4(l.position_radius.xyz, 1.0);
    gl_Position = g.projection * (center + vec4(v_offset * push.size, 0.0, 0.0));
}

#version 450

layout(location = 0) in vec2 v_offset;
layout(location = 1) flat in vec3 v_color;

layout(location = 0) out vec4 out_color;

void main() {
    float d2 = dot(v_offset, v_offset);
    if (d2 >= 1.0) {
        discard;
    }
    float glow = 1.0 - d2;
    out_color = vec4(mix(v_color, vec3(1.0), glow * glow * 0.6), glow);
}

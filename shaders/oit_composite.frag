#version 450

// Weighted blended transparency's composite (render/oit_pass.py): per pixel the accumulated
// premultiplied colour over its summed weight is the transparent surfaces' average colour, drawn
// over the scene by 1 - revealage (the "composite" blend: dst * revealage + colour * (1 - it)).
layout(set = 0, binding = 0) uniform sampler2D accumulated;
layout(set = 0, binding = 1) uniform sampler2D revealage;

layout(location = 0) out vec4 out_color;

void main() {
    ivec2 p = ivec2(gl_FragCoord.xy);
    float reveal = texelFetch(revealage, p, 0).r;
    if (reveal >= 1.0) {
        discard;  // no transparent surface here
    }
    vec4 sum = texelFetch(accumulated, p, 0);
    out_color = vec4(sum.rgb / clamp(sum.a, 1e-5, 5e4), reveal);
}

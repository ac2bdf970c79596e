#version 450
// A test's own "ldr" post effect (tests/test_post_plugin_external.py): the tone-mapped image
// darkened towards its corners, in linear colour (the _SRGB images decode on read, encode on
// write): colour * (1 - strength * r^2), r the distance from the centre in half-extents
// (1 at an edge's middle, sqrt 2 in a corner). texelFetch: no filtering to model.
layout(set = 0, binding = 0) uniform sampler2D source;
layout(push_constant) uniform Push {
    float strength;
} push;
layout(location = 0) out vec4 color;

void main() {
    ivec2 pixel = ivec2(gl_FragCoord.xy);
    vec2 size = vec2(textureSize(source, 0));
    vec2 r = (gl_FragCoord.xy / size) * 2.0 - 1.0;  // gl_FragCoord is the pixel's centre
    vec4 texel = texelFetch(source, pixel, 0);
    color = vec4(texel.rgb * max(1.0 - push.strength * dot(r, r), 0.0), texel.a);
}

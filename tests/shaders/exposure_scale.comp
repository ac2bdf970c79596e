#version 450
// A test's own "hdr" post effect (tests/test_post_plugin_external.py): the scene's HDR colour
// scaled in place by `scale` before the tone map (the storage image the bloom's composite
// writes too).
layout(local_size_x = 8, local_size_y = 8) in;
layout(set = 0, binding = 0, rgba16f) uniform image2D hdr;
layout(push_constant) uniform Push {
    float scale;
} push;

void main() {
    ivec2 pixel = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(pixel, imageSize(hdr)))) {
        return;
    }
    vec4 c = imageLoad(hdr, pixel);
    imageStore(hdr, pixel, vec4(c.rgb * push.scale, c.a));
}

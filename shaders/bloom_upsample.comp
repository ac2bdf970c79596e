#version 460
// One upsample step of the bloom chain (ecs_engine/render/post/bloom.py): the 3x3 tent filter
// of Jimenez's Call of Duty bloom (slide 162) over the smaller mip, blended into the larger one
// in place: target = target * push.dst + tent * push.src. For the energy-conserving composite
// dst = 1 - src (a convex mix: no light is made), for the additive one dst = 1. The last step
// writes the HDR image itself with the first mip's weight. tests/bloom_reference.py is the same
// arithmetic in NumPy.
layout(local_size_x = 8, local_size_y = 8) in;

layout(set = 0, binding = 0) uniform sampler2D source;
layout(set = 0, binding = 1, rgba16f) uniform image2D target;

layout(push_constant) uniform Push {
    float src;  // the smaller mip's weight (Bevy's blend factor)
    float dst;  // the larger one's
} push;

vec3 tap(vec2 uv, vec2 texel, float x, float y) {
    return textureLod(source, uv + vec2(x, y) * texel, 0.0).rgb;
}

void main() {
    ivec2 size = imageSize(target);
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (p.x >= size.x || p.y >= size.y) {
        return;
    }
    vec2 uv = (vec2(p) + 0.5) / vec2(size);
    vec2 texel = 1.0 / vec2(textureSize(source, 0));
    vec3 tent = tap(uv, texel, 0.0, 0.0) * 0.25;
    tent += (tap(uv, texel, 0.0, -1.0) + tap(uv, texel, -1.0, 0.0) + tap(uv, texel, 1.0, 0.0)
             + tap(uv, texel, 0.0, 1.0)) * 0.125;
    tent += (tap(uv, texel, -1.0, -1.0) + tap(uv, texel, 1.0, -1.0) + tap(uv, texel, -1.0, 1.0)
             + tap(uv, texel, 1.0, 1.0)) * 0.0625;
    vec4 old = imageLoad(target, p);
    imageStore(target, p, vec4(old.rgb * push.dst + tent * push.src, old.a));
}

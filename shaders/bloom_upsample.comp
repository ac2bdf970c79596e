#version 460
// One upsample step of the bloom chain (ecs_engine/render/post/bloom.py): the 3x3 tent filter
// of Jimenez's Call of Duty bloom (slide 162) over the smaller mip, blended into the larger one
// in place: target = target * push.dst + tent * push.src. For the energy-conserving composite
// dst = 1 - src (a convex mix: no light is made), for the additive one dst = 1. The last step
// writes the HDR image itself with the first mip's weight. tests/bloom_reference.py is the same
// arithmetic in NumPy. The target may be larger than the rectangle this view owns (a split-screen
// view's corner of the window's HDR image): sizes come from the push constants.
layout(local_size_x = 8, local_size_y = 8) in;

layout(set = 0, binding = 0) uniform sampler2D source;
layout(set = 0, binding = 1, rgba16f) uniform image2D target;

layout(push_constant) uniform Push {
    float src;  // the smaller mip's weight (Bevy's blend factor)
    float dst;  // the larger one's
    vec2 unused;
    vec2 source_size;  // the smaller mip (all of it)
    vec2 target_size;  // the rectangle written, texels from the target's corner (0, 0)
} push;

vec2 texel_scale;  // 1 / the whole source's size: texel coordinates to uv

// the bilinear sample (x, y) source texels from `at` (in texels), clamped as clamp-to-edge does
vec3 tap(vec2 at, float x, float y) {
    vec2 q = clamp(at + vec2(x, y), vec2(0.5), push.source_size - 0.5);
    return textureLod(source, q * texel_scale, 0.0).rgb;
}

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (p.x >= int(push.target_size.x) || p.y >= int(push.target_size.y)) {
        return;
    }
    texel_scale = 1.0 / vec2(textureSize(source, 0));
    vec2 at = (vec2(p) + 0.5) / push.target_size * push.source_size;
    vec3 tent = tap(at, 0.0, 0.0) * 0.25;
    tent += (tap(at, 0.0, -1.0) + tap(at, -1.0, 0.0) + tap(at, 1.0, 0.0)
             + tap(at, 0.0, 1.0)) * 0.125;
    tent += (tap(at, -1.0, -1.0) + tap(at, 1.0, -1.0) + tap(at, -1.0, 1.0)
             + tap(at, 1.0, 1.0)) * 0.0625;
    vec4 old = imageLoad(target, p);
    imageStore(target, p, vec4(old.rgb * push.dst + tent * push.src, old.a));
}

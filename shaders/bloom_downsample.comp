#version 460
// One downsample step of the bloom chain (ecs_engine/render/post/bloom.py): the 13-tap filter of
// Jimenez, "Next generation post processing in Call of Duty: Advanced Warfare" (SIGGRAPH 2014,
// slide 153), reading the level above through a linear, clamp-to-edge sampler and writing one
// mip of the half-resolution chain. Five overlapping 2x2 boxes (four corners weighted 0.125,
// the centre one 0.5): each tap is a bilinear sample, so 36 texels are read with 13 fetches and
// the result does not flicker as a bright pixel moves by one texel.
// The first step (FIRST) reads the HDR image: there the boxes are averaged with the Karis
// weights 1 / (1 + luma) (slide 168), normalised, so that one firefly pixel cannot make a bright
// blob, a flat field passes unchanged and no energy is added; then the optional soft threshold.
// tests/bloom_reference.py is the same arithmetic in NumPy.
// The source may be larger than the rectangle this view owns (a split-screen view's corner of
// the window's HDR image): every size comes from the push constants, and each tap's centre is
// clamped half a texel inside the rectangle, so a bilinear tap never reads a texel outside it
// (over a whole image this is what clamp-to-edge addressing gives).
layout(local_size_x = 8, local_size_y = 8) in;
layout(constant_id = 0) const uint FIRST = 0;

layout(set = 0, binding = 0) uniform sampler2D source;
layout(set = 0, binding = 1, rgba16f) uniform writeonly image2D target;

layout(push_constant) uniform Push {
    // threshold, threshold - knee, 2 knee, 0.25 / (knee + 1e-5); off where threshold <= 0
    vec4 threshold;
    vec2 source_size;  // the rectangle read, texels from the source's corner (0, 0)
    vec2 target_size;  // the rectangle written
} push;

const float HALF_MAX = 65504.0;  // the largest float16: an infinite HDR pixel stays finite

vec2 texel_scale;  // 1 / the whole source's size: texel coordinates to uv

// the bilinear sample (x, y) source texels from `at` (in texels), kept inside the rectangle
vec3 tap(vec2 at, float x, float y) {
    vec2 q = clamp(at + vec2(x, y), vec2(0.5), push.source_size - 0.5);
    return textureLod(source, q * texel_scale, 0.0).rgb;
}

float karis(vec3 c) {
    return 1.0 / (1.0 + dot(c, vec3(0.2126, 0.7152, 0.0722)));  // Rec. 709 luma
}

// Catlike Coding's soft knee, as Bevy's prefilter: off by default (physically, all light scatters).
vec3 soft_threshold(vec3 c) {
    float brightness = max(c.r, max(c.g, c.b));
    float soft = clamp(brightness - push.threshold.y, 0.0, push.threshold.z);
    soft = soft * soft * push.threshold.w;
    float contribution = max(brightness - push.threshold.x, soft) / max(brightness, 1e-5);
    return c * contribution;
}

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (p.x >= int(push.target_size.x) || p.y >= int(push.target_size.y)) {
        return;
    }
    texel_scale = 1.0 / vec2(textureSize(source, 0));
    vec2 at = (vec2(p) + 0.5) / push.target_size * push.source_size;
    vec3 a = tap(at, -2.0, -2.0), b = tap(at, 0.0, -2.0), c = tap(at, 2.0, -2.0);
    vec3 d = tap(at, -2.0, 0.0), e = tap(at, 0.0, 0.0), f = tap(at, 2.0, 0.0);
    vec3 g = tap(at, -2.0, 2.0), h = tap(at, 0.0, 2.0), i = tap(at, 2.0, 2.0);
    vec3 j = tap(at, -1.0, -1.0), k = tap(at, 1.0, -1.0);
    vec3 l = tap(at, -1.0, 1.0), m = tap(at, 1.0, 1.0);
    vec3 boxes[5] = vec3[5]((a + b + d + e) * 0.25, (b + c + e + f) * 0.25, (d + e + g + h) * 0.25,
                            (e + f + h + i) * 0.25, (j + k + l + m) * 0.25);
    const float weights[5] = float[5](0.125, 0.125, 0.125, 0.125, 0.5);
    vec3 sum = vec3(0.0);
    float total = 0.0;
    for (int n = 0; n < 5; n++) {
        float w = FIRST != 0u ? weights[n] * karis(boxes[n]) : weights[n];
        sum += boxes[n] * w;
        total += w;
    }
    vec3 color = sum / total;
    if (FIRST != 0u) {
        color = clamp(color, vec3(0.0), vec3(HALF_MAX));  // negative or infinite input
        if (push.threshold.x > 0.0) {
            color = soft_threshold(color);
        }
    }
    imageStore(target, p, vec4(color, 1.0));
}

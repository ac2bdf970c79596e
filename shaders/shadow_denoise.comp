#version 450
#extension GL_GOOGLE_include_directive : require
#include "layouts.glsl"

// The ray-traced shadows' small denoise (render/ray_shadows.py): the mask of a light traced with
// several rays (an area light, RayFrame.light_params.y > 1) is averaged over a 5 x 5 window of
// pixels weighted by a Gaussian and by how alike their surfaces are (depth within a few percent
// of this pixel's, normals facing alike), so the penumbra's noise fades and no shadow bleeds
// across an object's edge. A light traced with one ray (a hard shadow) is copied as it is.

layout(local_size_x = 8, local_size_y = 8) in;

layout(set = 0, binding = BINDING_RAY_FRAME, std430) readonly buffer Frame { RayFrame f; };
layout(set = 0, binding = BINDING_RAY_DEPTH) uniform sampler2D depth_image;
layout(set = 0, binding = BINDING_RAY_NORMAL, rgba32f) uniform readonly image2D normal_image;
layout(set = 0, binding = BINDING_RAY_MASK, rgba8) uniform readonly image2DArray traced;
layout(set = 0, binding = BINDING_RAY_DENOISED, rgba8) uniform writeonly image2DArray denoised;

const int RADIUS = 2;
const float DEPTH_TOLERANCE = 0.02;   // of this pixel's view distance

float view_distance(float depth, ivec2 pixel, ivec2 size) {
    vec2 ndc = (vec2(pixel) + 0.5) / vec2(size) * 2.0 - 1.0;
    vec4 v = f.inverse_projection * vec4(ndc, depth, 1.0);
    return length(v.xyz / v.w);
}

void main() {
    ivec2 pixel = ivec2(gl_GlobalInvocationID.xy);
    ivec2 size = ivec2(f.size.xy);
    if (any(greaterThanEqual(pixel, size))) {
        return;
    }
    uint lights = min(f.size.z, uint(MAX_RAY_LIGHTS));
    float depth = texelFetch(depth_image, pixel, 0).x;
    float here = depth > 0.0 ? view_distance(depth, pixel, size) : 0.0;
    vec3 n = imageLoad(normal_image, pixel).xyz;
    for (int layer = 0; layer * 4 < int(max(lights, 1u)); ++layer) {
        vec4 centre = imageLoad(traced, ivec3(pixel, layer));
        bvec4 soft = bvec4(false);
        for (int c = 0; c < 4; ++c) {
            uint i = uint(layer * 4 + c);
            soft[c] = i < lights && f.light_params[i].y > 1.0;
        }
        if (depth <= 0.0 || !any(soft)) {
            imageStore(denoised, ivec3(pixel, layer), centre);
            continue;
        }
        vec4 sum = vec4(0.0);
        float total = 0.0;
        for (int y = -RADIUS; y <= RADIUS; ++y) {
            for (int x = -RADIUS; x <= RADIUS; ++x) {
                ivec2 q = clamp(pixel + ivec2(x, y), ivec2(0), size - 1);
                float d = texelFetch(depth_image, q, 0).x;
                if (d <= 0.0) {
                    continue;
                }
                float there = view_distance(d, q, size);
                float alike = max(dot(n, imageLoad(normal_image, q).xyz), 0.0);
                float w = exp(-0.5 * float(x * x + y * y) / 2.25);
                w *= abs(there - here) <= DEPTH_TOLERANCE * here ? 1.0 : 0.0;
                w *= alike * alike * alike * alike;
                sum += w * imageLoad(traced, ivec3(q, layer));
                total += w;
            }
        }
        vec4 filtered = total > 0.0 ? sum / total : centre;
        imageStore(denoised, ivec3(pixel, layer), mix(centre, filtered, vec4(soft)));
    }
}

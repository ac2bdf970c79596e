#version 450

// The GTAO's spatial denoise (a depth-aware bilateral filter): the visibility averaged over 5 x 5
// pixels with weights 1/2, 1, 1, 1, 1/2 each way (so each of ssao_gtao.comp's 16 Bayer
// rotations weighs the same and the pattern cancels on a plane), each neighbour weighed down
// linearly to 0 by its distance from this pixel's tangent plane, 0 at `TOLERANCE` of this
// pixel's view depth (nothing bleeds across an object's silhouette). Out: the "ao" image.

layout(local_size_x = 8, local_size_y = 8) in;

layout(set = 0, binding = 0) uniform sampler2D depth_image;
layout(set = 0, binding = 1) uniform sampler2D noisy;  // visibility, view-space normal
layout(set = 0, binding = 2, r16f) uniform writeonly image2D ao;

layout(push_constant) uniform Params {
    mat4 inverse_projection;
    vec4 lens;
    vec4 shape;
    ivec4 counts;  // zw: the view's rectangle at the images' corner
} pc;

const float TOLERANCE = 0.05;
const float EDGE[5] = float[5](0.5, 1.0, 1.0, 1.0, 0.5);

ivec2 size;  // the rectangle, taken as the whole image (a split-screen view's is a corner)

vec3 view_position(ivec2 q, float d) {
    vec2 ndc = (vec2(q) + 0.5) / vec2(size) * 2.0 - 1.0;
    vec4 v = pc.inverse_projection * vec4(ndc, d, 1.0);
    return v.xyz / v.w;
}

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    size = pc.counts.zw;
    if (any(greaterThanEqual(p, size))) return;
    vec4 centre = texelFetch(noisy, p, 0);
    float d = texelFetch(depth_image, p, 0).x;
    if (d <= 0.0) {
        imageStore(ao, p, vec4(centre.x));
        return;
    }
    vec3 c = view_position(p, d);
    float tolerance = max(TOLERANCE * abs(c.z), 1e-6);  // an orthographic near plane may be at 0
    float sum = 0.0;
    float total = 0.0;
    for (int y = -2; y <= 2; ++y) {
        for (int x = -2; x <= 2; ++x) {
            ivec2 q = clamp(p + ivec2(x, y), ivec2(0), size - 1);
            float dq = texelFetch(depth_image, q, 0).x;
            if (dq <= 0.0) continue;
            float off_plane = abs(dot(centre.yzw, view_position(q, dq) - c));
            float w = EDGE[x + 2] * EDGE[y + 2] * max(1.0 - off_plane / tolerance, 0.0);
            sum += w * texelFetch(noisy, q, 0).x;
            total += w;
        }
    }
    imageStore(ao, p, vec4(sum / total));  // total >= 1: the pixel itself
}

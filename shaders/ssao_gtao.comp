#version 450

// Ground-truth ambient occlusion (GTAO, Jimenez et al. 2016) after Intel's XeGTAO and Bevy's
// gtao.wgsl: for each pixel, `slices` screen directions; along each, the highest horizon on
// either side within `radius` metres (`steps` depth samples a side, squared spacing, whole
// pixels), then the cosine-weighted visible arc between the two horizons, integrated
// analytically against the normal projected into the slice. Depth only: the view-space position
// comes from the reverse-Z depth through the inverse projection and the normal from the
// neighbours' positions (the side with the smaller depth step, so edges do not bend it).
// The rotation of the slices and the jitter of the steps come from a fixed 4 x 4 Bayer matrix
// (ssao_denoise.comp's 5 x 5 window weighs all 16 alike), so tests/ssao_reference.py matches.
// Out: rgba16f (visibility, view-space normal) for the denoise; 1 where nothing was drawn.

layout(local_size_x = 8, local_size_y = 8) in;

layout(set = 0, binding = 0) uniform sampler2D depth_image;
layout(set = 0, binding = 1, rgba16f) uniform writeonly image2D noisy;

layout(push_constant) uniform Params {
    mat4 inverse_projection;  // clip -> view space (reverse-Z: depth 1 at near, 0 far/infinity)
    vec4 lens;                // x: 0.5 * P[0][0] * width; clip w = y * z_view + z; w: radius (m)
    vec4 shape;               // x: intensity (exponent), y: falloff (fraction of the radius)
    ivec4 counts;             // x: slices, y: steps a side, zw: the view's rectangle (below)
} pc;

const float PI = 3.14159265358979;
const float HALF_PI = 1.57079632679490;
const int BAYER[16] = int[16](0, 8, 2, 10, 12, 4, 14, 6, 3, 11, 1, 9, 15, 7, 13, 5);

// The view's rectangle at the images' corner, taken as the whole image (a split-screen view's
// depth is a corner of the window's: its texture size is not the view's).
ivec2 size;

float depth_at(ivec2 q) {
    return texelFetch(depth_image, clamp(q, ivec2(0), size - 1), 0).x;
}

vec3 view_position(ivec2 q, float d) {
    vec2 ndc = (vec2(q) + 0.5) / vec2(size) * 2.0 - 1.0;
    vec4 v = pc.inverse_projection * vec4(ndc, d, 1.0);
    return v.xyz / v.w;
}

// The step from the pixel to its neighbour along `axis`: towards the one nearer in depth; a
// neighbour off the image or on the background is not taken.
vec3 tangent(ivec2 p, vec3 c, ivec2 axis) {
    ivec2 a = p - axis;
    ivec2 b = p + axis;
    float da = depth_at(a);
    float db = depth_at(b);
    bool has_a = all(greaterThanEqual(a, ivec2(0))) && da > 0.0;
    bool has_b = all(lessThan(b, size)) && db > 0.0;
    vec3 to_a = has_a ? c - view_position(a, da) : vec3(0.0);
    vec3 to_b = has_b ? view_position(b, db) - c : vec3(0.0);
    if (!has_a) return to_b;
    if (!has_b) return to_a;
    return abs(to_a.z) < abs(to_b.z) ? to_a : to_b;
}

// cos of the horizon a sample raises (the slice's lowest, the tangent plane, beyond the
// falloff); off the image nothing is known: no occluder (a clamped sample would lie off the
// slice and occlude the image's border)
float horizon(ivec2 q, vec3 c, vec3 view_vec, float low, float falloff_mul, float falloff_add) {
    if (any(lessThan(q, ivec2(0))) || any(greaterThanEqual(q, size))) return low;
    float d = depth_at(q);
    if (d <= 0.0) return low;
    vec3 delta = view_position(q, d) - c;
    float dist = length(delta);
    float weight = clamp(dist * falloff_mul + falloff_add, 0.0, 1.0);
    return mix(low, dot(delta / dist, view_vec), weight);
}

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    size = pc.counts.zw;
    if (any(greaterThanEqual(p, size))) return;
    float d = depth_at(p);
    if (d <= 0.0) {
        imageStore(noisy, p, vec4(1.0, 0.0, 0.0, 0.0));
        return;
    }
    vec3 c = view_position(p, d);
    vec3 view_vec = normalize(-c);
    // x right, y down in pixels: cross(down, right) faces the camera
    vec3 normal = cross(tangent(p, c, ivec2(0, 1)), tangent(p, c, ivec2(1, 0)));
    float normal_length = length(normal);
    normal = normal_length > 0.0 ? normal / normal_length : view_vec;

    float radius = pc.lens.w;
    float pixel_radius = radius * pc.lens.x / (pc.lens.y * c.z + pc.lens.z);
    c *= 0.99999;  // towards the eye: a plane does not occlude itself through rounding
    float falloff_range = pc.shape.y * radius;
    float falloff_mul = -1.0 / falloff_range;
    float falloff_add = radius * (1.0 - pc.shape.y) / falloff_range + 1.0;
    float min_s = 1.3 / pixel_radius;  // the first sample at least a pixel away

    float slice_noise = (float(BAYER[(p.y & 3) * 4 + (p.x & 3)]) + 0.5) / 16.0;
    float step_noise = (float(BAYER[(p.x & 3) * 4 + (p.y & 3)]) + 0.5) / 16.0;
    int slices = pc.counts.x;
    int steps = pc.counts.y;
    float visibility = 0.0;
    for (int slice = 0; slice < slices; ++slice) {
        float phi = (float(slice) + slice_noise) * (PI / float(slices));
        vec2 omega = vec2(cos(phi), sin(phi));
        vec3 direction = vec3(omega.x, -omega.y, 0.0);  // view space: y up
        vec3 ortho = direction - dot(direction, view_vec) * view_vec;
        vec3 axis = normalize(cross(ortho, view_vec));
        vec3 projected = normal - axis * dot(normal, axis);
        float projected_length = length(projected);
        float cos_n = clamp(dot(projected, view_vec) / max(projected_length, 1e-6), 0.0, 1.0);
        float n = sign(dot(ortho, projected)) * acos(cos_n);
        float low0 = cos(n + HALF_PI);
        float low1 = cos(n - HALF_PI);
        float cos0 = low0;
        float cos1 = low1;
        for (int i = 0; i < steps; ++i) {
            float jitter = fract(step_noise + float(slice + i * steps) * 0.618034);
            float s = (float(i) + jitter) / float(steps);
            s = s * s + min_s;
            ivec2 offset = ivec2(floor((s * pixel_radius) * omega + 0.5));
            cos0 = max(cos0, horizon(p + offset, c, view_vec, low0, falloff_mul, falloff_add));
            cos1 = max(cos1, horizon(p - offset, c, view_vec, low1, falloff_mul, falloff_add));
        }
        projected_length = mix(projected_length, 1.0, 0.05);
        float h0 = -acos(clamp(cos1, -1.0, 1.0));
        float h1 = acos(clamp(cos0, -1.0, 1.0));
        h0 = n + clamp(h0 - n, -HALF_PI, HALF_PI);
        h1 = n + clamp(h1 - n, -HALF_PI, HALF_PI);
        float arc0 = (cos_n + 2.0 * h0 * sin(n) - cos(2.0 * h0 - n)) / 4.0;
        float arc1 = (cos_n + 2.0 * h1 * sin(n) - cos(2.0 * h1 - n)) / 4.0;
        visibility += projected_length * (arc0 + arc1);
    }
    visibility = pow(clamp(visibility / float(slices), 0.03, 1.0), pc.shape.x);
    imageStore(noisy, p, vec4(visibility, normal));
}

#version 450

// The fallback use of the "ao" image until the lit shaders read it: the HDR colour multiplied
// by it in place. Physically AO darkens only the ambient / indirect light (see
// ecs_engine/render/post/ssao.py); this darkens direct light too.

layout(local_size_x = 8, local_size_y = 8) in;

layout(set = 0, binding = 0) uniform sampler2D ao;
layout(set = 0, binding = 1, rgba16f) uniform image2D hdr;

// only counts.zw: the view's rectangle at the HDR image's corner (a split-screen view's is a corner
// of the window's image: imageSize would be the window's)
layout(push_constant) uniform Params {
    mat4 inverse_projection;
    vec4 lens;
    vec4 shape;
    ivec4 counts;
} pc;

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    ivec2 size = pc.counts.zw;
    if (any(greaterThanEqual(p, size))) return;
    float visibility = texelFetch(ao, clamp(p, ivec2(0), textureSize(ao, 0) - 1), 0).x;
    vec4 colour = imageLoad(hdr, p);
    imageStore(hdr, p, vec4(colour.rgb * visibility, colour.a));
}

#version 450
#extension GL_GOOGLE_include_directive : require
#include "common.glsl"

// ray-traced shadows' mask (render/ray_shadows.py), read by light_shadow at this pixel
layout(set = SET_DEFERRED, binding = BINDING_SHADOW_MASK, rgba8) uniform readonly image2DArray shadow_mask;
ivec2 g_pixel;
float ray_shadow_mask(uint light) {
    return imageLoad(shadow_mask, ivec3(g_pixel, int(light / 4u)))[light % 4u];
}
#define RAY_SHADOW_MASK
#include "shading.glsl"
#include "light_grid.glsl"

// The deferred form's lighting (render/deferred_pass.py): one workgroup per DEFERRED_TILE square
// of pixels adds every light's term to the HDR colour the G-buffer pass left (ambient, emissive).
// The same light_term as the forward fragment shader, from the pixel's position (rebuilt from
// depth), normal, base colour, metallic and roughness (the G-buffer) and the rest of its material.
//
// With the light grid (g.light_tiles.x > 0, render/light_clusters.py) the workgroup first finds
// the nearest and farthest lit pixel, takes the light index range of the distance bins between
// them, and keeps in shared memory the mask bits of its screen tile(s) in that range whose
// sphere reaches that distance shell; then every pixel walks those bits, testing each light's
// sphere before the full term. Without it, every pixel loops over every light.
layout(local_size_x = DEFERRED_TILE, local_size_y = DEFERRED_TILE) in;

layout(set = SET_DEFERRED, binding = BINDING_DEPTH) uniform sampler2D depth_image;
layout(set = SET_DEFERRED, binding = BINDING_HDR, rgba16f) uniform image2D hdr_image;
layout(set = SET_DEFERRED, binding = BINDING_NORMAL_ROUGHNESS, rgba32f) uniform readonly image2D normal_image;
layout(set = SET_DEFERRED, binding = BINDING_BASE_METALLIC, rgba16f) uniform readonly image2D base_image;
layout(set = SET_DEFERRED, binding = BINDING_MATERIAL_IDS, r32ui) uniform readonly uimage2D material_image;

layout(push_constant) uniform Push { DeferredPush push; };

const uint GROUP = DEFERRED_TILE * DEFERRED_TILE;
shared uint s_near, s_far;   // the lit pixels' distances from the eye (float bits: positive floats order as uints)
shared uint s_lo, s_hi;      // the light index range of the distance bins between them
shared uint s_words[DEFERRED_WORDS];

// Light i's bounding sphere in view space (light_bounds.comp) reaches distances [near, far] from the eye.
bool reaches_shell(uint i, float near, float far) {
    uint at = g.light_bins.x + 4u * i;
    vec3 c = vec3(uintBitsToFloat(cluster_data[at]), uintBitsToFloat(cluster_data[at + 1u]),
                  uintBitsToFloat(cluster_data[at + 2u]));
    float r = uintBitsToFloat(cluster_data[at + 3u]);
    float d = length(c);
    return r > 0.0 && d - r <= far && d + r >= near;
}

// Mask word w of the light grid's tiles under this workgroup, ORed (one tile unless the grid's
// tiles are smaller than the workgroup's).
uint tile_word(uint w, uvec2 first_tile, uvec2 last_tile) {
    uint bits = 0u;
    for (uint y = first_tile.y; y <= last_tile.y; ++y) {
        for (uint x = first_tile.x; x <= last_tile.x; ++x) {
            bits |= cluster_data[g.light_bins.y + (y * g.light_tiles.x + x) * g.light_tiles.z + w];
        }
    }
    return bits;
}

void main() {
    ivec2 size = min(ivec2(push.viewport), imageSize(hdr_image));   // what the rasteriser's viewport covered
    ivec2 pixel = ivec2(gl_GlobalInvocationID.xy);
    g_pixel = pixel;
    uint local = gl_LocalInvocationIndex;
    uint index = all(lessThan(pixel, size)) ? imageLoad(material_image, pixel).x : NO_MATERIAL;
    bool lit = index != NO_MATERIAL;
    Material m;
    uint model = 0u;
    vec3 p = vec3(0.0), n = vec3(0.0, 0.0, 1.0), to_eye = vec3(0.0, 0.0, 1.0);
    float distance = 0.0;
    bool shadowed = true;
    if (lit) {
        float depth = texelFetch(depth_image, pixel, 0).x;
        vec2 ndc = (vec2(pixel) + 0.5) / vec2(size) * 2.0 - 1.0;
        vec4 v = g.inverse_projection * vec4(ndc, depth, 1.0);
        v.xyz /= v.w;
        p = transpose(mat3(g.view)) * (v.xyz - g.view[3].xyz);   // the view is a rotation and a translation
        vec4 nr = imageLoad(normal_image, pixel);
        vec4 bm = imageLoad(base_image, pixel);
        m = materials[index & 0x7FFFFFFFu];
        shadowed = (index >> 31) == 0u;   // bit 31: NotShadowReceiver
        m.base_color.rgb = bm.rgb;   // after the base colour texture
        m.surface.x = bm.a;          // metallic and roughness after theirs
        m.surface.y = nr.a;
        model = m.kind.x;
        n = nr.xyz;
        vec3 eye = g.eye.xyz - p;
        distance = sqrt(dot(eye, eye));   // the light grid's bins are shells around the camera's position
        to_eye = eye_direction(p);
    }
    vec3 color = vec3(0.0);
    if (g.light_tiles.x == 0u) {
        for (uint i = 0u; lit && i < g.counts.x; ++i) {
            color += light_term(i, m, model, p, n, to_eye, shadowed);
        }
    } else {
        uint globals = min(cluster_data[0], uint(MAX_GLOBAL_LIGHTS));
        for (uint k = 0u; lit && k < globals; ++k) {
            color += light_term(cluster_data[CLUSTER_GLOBALS + k], m, model, p, n, to_eye, shadowed);
        }
        if (local == 0u) {
            s_near = floatBitsToUint(3.0e38);
            s_far = 0u;
            s_lo = 0xFFFFFFFFu;
            s_hi = 0u;
        }
        barrier();
        if (lit) {
            atomicMin(s_near, floatBitsToUint(distance));
            atomicMax(s_far, floatBitsToUint(distance));
        }
        barrier();
        float near = uintBitsToFloat(s_near), far = uintBitsToFloat(s_far);
        bool any_lit = s_far >= s_near;   // uniform
        uint bin_first = light_bin(near), bin_last = light_bin(far);
        for (uint b = bin_first + local; any_lit && b <= bin_last; b += GROUP) {
            atomicMin(s_lo, cluster_data[CLUSTER_HEADER + b]);
            atomicMax(s_hi, cluster_data[CLUSTER_HEADER + LIGHT_BINS + b]);
        }
        barrier();
        uint lo = s_lo, hi = min(s_hi, g.counts.y - 1u);
        uvec2 corner = gl_WorkGroupID.xy * DEFERRED_TILE;
        uvec2 last_tile = min((corner + (DEFERRED_TILE - 1u)) / g.light_tiles.w, g.light_tiles.xy - 1u);
        uvec2 first_tile = min(corner / g.light_tiles.w, last_tile);
        uint first_word = lo >> 5u, last_word = hi >> 5u;
        // uniform: every invocation takes the same turns, so the barriers are met by all
        for (uint base = first_word; any_lit && lo <= hi && base <= last_word; base += DEFERRED_WORDS) {
            uint words = min(uint(DEFERRED_WORDS), last_word + 1u - base);
            for (uint k = local; k < words; k += GROUP) {
                uint w = base + k;
                uint bits = tile_word(w, first_tile, last_tile);
                if (w == first_word) {
                    bits &= ~0u << (lo & 31u);
                }
                if (w == last_word) {
                    bits &= ~0u >> (31u - (hi & 31u));
                }
                uint kept = 0u;
                while (bits != 0u) {
                    uint j = uint(findLSB(bits));
                    bits &= bits - 1u;
                    kept |= reaches_shell(w * 32u + j, near, far) ? 1u << j : 0u;
                }
                s_words[k] = kept;
            }
            barrier();
            for (uint k = 0u; lit && k < words; ++k) {
                uint bits = s_words[k];
                while (bits != 0u) {
                    uint j = uint(findLSB(bits));
                    bits &= bits - 1u;
                    uint i = (base + k) * 32u + j;
                    vec4 sphere = lights[i].position_radius;
                    vec3 to_light = sphere.xyz - p;
                    if (dot(to_light, to_light) < sphere.w * sphere.w) {
                        color += light_term(i, m, model, p, n, to_eye, shadowed);
                    }
                }
            }
            barrier();
        }
    }
    if (lit) {
        vec4 c = imageLoad(hdr_image, pixel);
        imageStore(hdr_image, pixel, vec4(min(c.rgb + color, vec3(65504.0)), c.a));
    }
}

// The mesh fragment shader body: mesh.frag, and mesh_textured.frag (TEXTURED: the material's
// textures, sampled from the texture pages; render/texture_pages.py says why pages).
#include "light_grid.glsl"
#include "environment.glsl"

layout(location = 0) in vec3 v_position;
layout(location = 1) in vec3 v_normal;
layout(location = 2) flat in uint v_material;
#ifdef TEXTURED
layout(location = 3) in vec2 v_uv;
layout(location = 4) in vec4 v_tangent;

#include "texture_pages.glsl"
#endif

layout(location = 0) out vec4 out_color;
#ifdef OIT
// weighted blended transparency (render/oit_pass.py): the revealage target
layout(location = 1) out float out_reveal;
#endif
#ifdef GBUFFER
// the deferred form's first pass (gpu/gbuffer.py): what render/deferred_pass.py lights the pixel with
layout(location = 1) out vec4 out_normal_roughness;
layout(location = 2) out vec4 out_base_metallic;
layout(location = 3) out uint out_material;
#endif

// Where the light mask of this fragment's screen tile starts (light_grid.glsl).
uint tile_masks() {
    uvec2 tile = min(uvec2(gl_FragCoord.xy) / g.light_tiles.w, g.light_tiles.xy - 1u);
    return g.light_bins.y + (tile.y * g.light_tiles.x + tile.x) * g.light_tiles.z;
}

// The material's shading model, per fragment, over every light (or, with GBUFFER, what the
// lighting pass needs). Every division is guarded, so a
// fragment at a light's centre, a light of radius or intensity 0, or a degenerate normal stays finite.
void main() {
    Material m = materials[v_material & 0x7FFFFFFFu];
    bool shadowed = (v_material >> 31) == 0u;   // bit 31: NotShadowReceiver (mesh_vertex.glsl)
    float occlusion = 1.0;
    vec3 n = v_normal;
    if ((MATERIAL_FEATURES & FEATURE_DOUBLE_SIDED) != 0u && !gl_FrontFacing) {
        if (m.kind.z == 0u) {
            discard;  // culling is off for the double-sided: a single-sided back face is not drawn
        }
        n = -n;  // glTF: the back face is lit with the normal reversed (the bitangent follows it)
    }
#ifdef TEXTURED
    vec2 dx = dFdx(v_uv), dy = dFdy(v_uv);
    if (m.textures.x != NO_TEXTURE) {
        m.base_color *= sample_texture(m.textures.x, v_uv, dx, dy);
    }
    if (m.textures.y != NO_TEXTURE) {
        vec4 mr = sample_texture(m.textures.y, v_uv, dx, dy);
        m.surface.y *= mr.g;
        m.surface.x *= mr.b;
    }
    if ((MATERIAL_FEATURES & FEATURE_EMISSIVE) != 0u && m.textures.w != NO_TEXTURE) {
        m.emissive.rgb *= sample_texture(m.textures.w, v_uv, dx, dy).rgb;
    }
    if (m.textures2.x != NO_TEXTURE) {
        occlusion = 1.0 + m.params.z * (sample_texture(m.textures2.x, v_uv, dx, dy).r - 1.0);
    }
#endif
    if ((MATERIAL_FEATURES & FEATURE_ALPHA_MASK) != 0u && m.kind.y == ALPHA_MASK && m.base_color.a < m.params.x) {
        discard;
    }
    uint model = m.kind.x;
    vec3 color = m.base_color.rgb;
#ifdef GBUFFER
    out_normal_roughness = vec4(0.0);
    out_base_metallic = vec4(0.0);
    out_material = NO_MATERIAL;  // unlit: nothing for the lighting pass to add
#endif
    if (!model_is(model, MODEL_UNLIT)) {
        float n2 = dot(n, n);
        if (n2 < 1e-24) {
            n = cross(dFdx(v_position), dFdy(v_position));   // flattened geometry: face normal
            n2 = dot(n, n);
        }
        n = n2 > 1e-24 ? n * inversesqrt(n2) : vec3(0.0, 0.0, 1.0);
#ifdef TEXTURED
        if (m.textures.z != NO_TEXTURE) {
            // tangent-space normal: x along +u, y along the bitangent w * cross(n, t) (glTF)
            vec3 t = v_tangent.xyz - n * dot(n, v_tangent.xyz);
            float t2 = dot(t, t);
            if (t2 > 1e-24) {
                t *= inversesqrt(t2);
                vec3 b = v_tangent.w * cross(n, t);
                vec3 tn = sample_texture(m.textures.z, v_uv, dx, dy).xyz * 2.0 - 1.0;
                tn.xy *= m.params.y;
                vec3 mapped = t * tn.x + b * tn.y + n * tn.z;
                float m2 = dot(mapped, mapped);
                n = m2 > 1e-24 ? mapped * inversesqrt(m2) : n;
            }
        }
#endif
        vec3 to_eye = eye_direction(v_position);
        bool environment = (MATERIAL_FEATURES & FEATURE_ENVIRONMENT) != 0u;
        if (environment && g.environment.z > 0.0) {
            color = environment_ambient(m, model, n, to_eye, occlusion);   // image-based ambient
        } else {
            color = g.ambient.rgb * (g.ambient.a * occlusion) * m.base_color.rgb;
        }
#if defined(GBUFFER)
        out_normal_roughness = vec4(n, m.surface.y);
        out_base_metallic = vec4(m.base_color.rgb, m.surface.x);
        out_material = v_material;   // with its NotShadowReceiver bit
#elif defined(CLUSTERED)
        {
            uint globals = min(cluster_data[0], uint(MAX_GLOBAL_LIGHTS));
            for (uint k = 0u; k < globals; ++k) {
                color += light_term(cluster_data[CLUSTER_GLOBALS + k], m, model, v_position, n, to_eye, shadowed);
            }
            // the lights of this fragment's distance bin (an index range) and screen tile (a mask),
            // walked once for the whole subgroup (M. Drobot's scalarisation): the light index is
            // then uniform, so its row is read once for all. Each invocation adds only the lights
            // of its own cluster whose sphere holds the fragment (most candidates miss it).
            vec3 eye = g.eye.xyz - v_position;   // the bins are shells around the camera's position
            uint bin = light_bin(sqrt(dot(eye, eye)));
            uint lo = cluster_data[CLUSTER_HEADER + bin];
            uint hi = cluster_data[CLUSTER_HEADER + LIGHT_BINS + bin];
            uint masks = tile_masks();
            // (bounded: helper invocations may be left out of the subgroup's operations)
            uint first = subgroupMin(lo), last = min(subgroupMax(hi), g.counts.y - 1u);
            for (uint w = first >> 5u; first <= last && w <= (last >> 5u); ++w) {
                uint bits = lo <= hi && w >= (lo >> 5u) && w <= (hi >> 5u) ? cluster_data[masks + w] : 0u;
                if (w == (lo >> 5u)) {
                    bits &= ~0u << (lo & 31u);
                }
                if (w == (hi >> 5u)) {
                    bits &= ~0u >> (31u - (hi & 31u));
                }
                uint any = subgroupOr(bits);
                while (any != 0u) {
                    uint j = uint(findLSB(any));
                    any &= any - 1u;
                    uint i = w * 32u + j;
                    vec4 sphere = lights[i].position_radius;
                    vec3 to_light = sphere.xyz - v_position;
                    if ((bits & (1u << j)) != 0u && dot(to_light, to_light) < sphere.w * sphere.w) {
                        color += light_term(i, m, model, v_position, n, to_eye, shadowed);
                    }
                }
            }
        }
#else
        for (uint i = 0u; i < g.counts.x; ++i) {
            color += light_term(i, m, model, v_position, n, to_eye, shadowed);
        }
#endif
#ifndef GBUFFER
        if (environment) {   // mirroring materials are drawn forward (Materials.set_aside), never here with GBUFFER
            color = environment_surface(color, m, n, to_eye);
        }
#endif
    }
    if ((MATERIAL_FEATURES & FEATURE_EMISSIVE) != 0u) {
        color += m.emissive.rgb;
    }
#ifdef OIT
    // McGuire and Bavoil, "Weighted blended order-independent transparency" (2013), eq. 10 on
    // the distance d from the eye: nearer surfaces weigh more; the sums are order-independent
    float a = clamp(m.base_color.a, 0.0, 1.0);
    float d = length(g.eye.xyz - v_position);
    float d5 = d / 5.0, d200 = d / 200.0;
    float w = a * clamp(10.0 / (1e-5 + d5 * d5 + d200 * d200 * d200 * d200 * d200 * d200), 1e-2, 3e3);
    out_color = vec4(min(color, vec3(65504.0)) * a, a) * w;
    out_reveal = a;
#else
    // alpha matters only to the blended materials' pipelines (the others do not blend)
    bool blended = (MATERIAL_FEATURES & FEATURE_BLEND) != 0u && m.kind.y == ALPHA_BLEND;
    out_color = vec4(min(color, vec3(65504.0)), blended ? m.base_color.a : 1.0);
#endif
}

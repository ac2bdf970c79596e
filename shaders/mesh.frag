#version 450
#extension GL_GOOGLE_include_directive : require
#include "common.glsl"
#include "shading.glsl"

layout(location = 0) in vec3 v_position;
layout(location = 1) in vec3 v_normal;
layout(location = 2) flat in uint v_material;

layout(location = 0) out vec4 out_color;

// The material's shading model, per fragment, over every light. Every division is guarded, so a
// fragment at a light's centre, a light of radius or intensity 0, or a degenerate normal stays finite.
void main() {
    Material m = materials[v_material];
    if ((MATERIAL_FEATURES & FEATURE_ALPHA_MASK) != 0u && m.kind.y == ALPHA_MASK && m.base_color.a < m.params.x) {
        discard;
    }
    uint model = m.kind.x;
    vec3 color = m.base_color.rgb;
    if (!model_is(model, MODEL_UNLIT)) {
        vec3 n = v_normal;
        float n2 = dot(n, n);
        if (n2 < 1e-24) {
            n = cross(dFdx(v_position), dFdy(v_position));   // flattened geometry: face normal
            n2 = dot(n, n);
        }
        n = n2 > 1e-24 ? n * inversesqrt(n2) : vec3(0.0, 0.0, 1.0);
        vec3 eye = g.eye.xyz - v_position;
        float e2 = dot(eye, eye);
        vec3 to_eye = e2 > 1e-24 ? eye * inversesqrt(e2) : vec3(0.0, 0.0, 1.0);
        color = g.ambient.rgb * g.ambient.a * m.base_color.rgb;
        for (uint i = 0u; i < g.counts.x; ++i) {
            Light light = lights[i];
            vec3 l;
            float energy = light_at(light, v_position, n, l);
            float nl = dot(n, l);
            if (nl > 0.0 && energy > 0.0) {
                color += light.color_intensity.rgb * (energy * nl) * brdf_pi(m, model, n, l, to_eye, nl);
            }
        }
    }
    color += m.emissive.rgb;
    out_color = vec4(min(color, vec3(65504.0)), 1.0);
}

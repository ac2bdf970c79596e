#version 450
#extension GL_GOOGLE_include_directive : require
#include "common.glsl"

layout(location = 0) in vec3 v_position;
layout(location = 1) in vec3 v_normal;
layout(location = 2) flat in uint v_material;

layout(location = 0) out vec4 out_color;

// Blinn-Phong, per fragment, over every point light. Every division is guarded, so a fragment
// at a light's centre, a light of radius or intensity 0, or a degenerate normal stays finite.
void main() {
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

    Material m = materials[v_material];
    vec3 color = g.ambient.rgb * g.ambient.a * m.color.rgb;
    for (uint i = 0u; i < g.counts.x; ++i) {
        Light l = lights[i];
        vec3 to_light = l.position_radius.xyz - v_position;
        float d2 = dot(to_light, to_light);
        float r = l.position_radius.w;
        float window = 1.0;
        if (r > 0.0) {
            float q = d2 / (r * r);
            window = clamp(1.0 - q * q, 0.0, 1.0);
            window *= window;
        }
        // capped: an infinite energy times a zero diffuse term would be NaN
        float energy = min(l.color_intensity.w * window / max(d2, 1e-4), 65504.0);
        vec3 dir = d2 > 1e-24 ? to_light * inversesqrt(d2) : n;
        float diffuse = max(dot(n, dir), 0.0);
        vec3 h = dir + to_eye;
        float h2 = dot(h, h);
        float spec = 0.0;
        if (diffuse > 0.0 && h2 > 1e-24) {
            spec = pow(max(dot(n, h * inversesqrt(h2)), 0.0), max(m.specular.y, 1.0)) * m.specular.x;
        }
        color += l.color_intensity.rgb * energy * (diffuse * m.color.rgb + spec);
    }
    out_color = vec4(min(color, vec3(65504.0)), 1.0);  // thousands of bright lights: finite
}

#version 450
#extension GL_GOOGLE_include_directive : require
#include "common.glsl"

// The Environment's cube map seen through each pixel: the view ray from the projection (a
// symmetric perspective: x / P00, y / P11, looking down -Z; an orthographic camera looks down -Z
// everywhere), turned into the world's axes by the view's rotation (transposed), times the intensity.
layout(location = 0) in vec2 v_ndc;
layout(location = 0) out vec4 out_color;

void main() {
    vec3 ray = g.projection[3][3] == 1.0
        ? vec3(0.0, 0.0, -1.0)
        : vec3(v_ndc.x / g.projection[0][0], v_ndc.y / g.projection[1][1], -1.0);
    vec3 d = transpose(mat3(g.view)) * ray;
    out_color = vec4(min(textureLod(environment_map, d, 0.0).rgb * g.environment.x, vec3(65504.0)), 1.0);
}

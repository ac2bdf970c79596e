#version 450

// The sky (render/sky_pass.py): one triangle covering the screen at depth 0, the far plane of
// reverse-Z, so it is drawn only where nothing else was (its depth test passes on equal).
layout(location = 0) out vec2 v_ndc;

void main() {
    vec2 p = vec2((gl_VertexIndex << 1) & 2, gl_VertexIndex & 2) * 2.0 - 1.0;
    v_ndc = p;
    gl_Position = vec4(p, 0.0, 1.0);
}

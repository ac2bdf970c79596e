#version 450
#extension GL_GOOGLE_include_directive : require
// Shadow maps of scenes with alpha-masked or double-sided materials (render/chunk_paths.py's
// shadow_pipelines): where an alpha-masked material's alpha (its factor times its base colour
// texture's) is below its cutoff, nothing is drawn into the map, so light passes through the
// holes as it does on screen. With a double-sided material in the scene culling is off, and a
// single-sided material's back faces are dropped here, as mesh_fragment.glsl drops them on
// screen: a single-sided caster holds the light with its front alone, as it does without.
#include "common.glsl"
#include "texture_pages.glsl"

layout(constant_id = 0) const uint MATERIAL_FEATURES = 0xFFFFFFFFu;

layout(location = 0) in vec2 v_uv;
layout(location = 1) flat in uint v_material;

void main() {
    vec2 dx = dFdx(v_uv), dy = dFdy(v_uv);  // before any branch (derivatives need the whole quad)
    Material m = materials[v_material];
    if ((MATERIAL_FEATURES & FEATURE_DOUBLE_SIDED) != 0u && !gl_FrontFacing && m.kind.z == 0u) {
        discard;
    }
    if ((MATERIAL_FEATURES & FEATURE_ALPHA_MASK) == 0u || m.kind.y != ALPHA_MASK) {
        return;
    }
    float alpha = m.base_color.a;
    if ((MATERIAL_FEATURES & FEATURE_TEXTURES) != 0u && m.textures.x != NO_TEXTURE) {
        alpha *= sample_texture(m.textures.x, v_uv, dx, dy).a;
    }
    if (alpha < m.params.x) {
        discard;
    }
}

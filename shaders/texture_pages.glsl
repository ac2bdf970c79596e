// The material textures, layers of the texture pages (render/texture_pages.py says why pages):
// for mesh_fragment.glsl's textured variants and the shadow cutouts (shadow_cutout.frag).
layout(set = SET_FRAME, binding = BINDING_TEXTURES) uniform sampler2DArray texture_pages[TEXTURE_PAGES];

// A texture ref is page << 16 | layer. Constant indices in a switch, and explicit gradients taken
// before any branch: legal on every device, descriptor indexing or not.
#define PAGE(i) case i: return textureGrad(texture_pages[i], at, dx, dy);
vec4 sample_texture(uint ref, vec2 uv, vec2 dx, vec2 dy) {
    vec3 at = vec3(uv, float(ref & 0xFFFFu));
    switch (ref >> 16) {
        PAGE(0) PAGE(1) PAGE(2) PAGE(3) PAGE(4) PAGE(5) PAGE(6) PAGE(7) PAGE(8)
        PAGE(9) PAGE(10) PAGE(11) PAGE(12) PAGE(13) PAGE(14) PAGE(15) PAGE(16) PAGE(17)
    }
    return vec4(1.0);
}

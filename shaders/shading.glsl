// Shading models and light falloff, for mesh.frag. The model is the material's (Material.kind.x);
// MATERIAL_FEATURES, a specialisation constant, has a bit per model some material of the scene
// uses, so the driver compiles only those branches (render/materials.py keeps the bits).
//
// Units (components/light.py): a light delivers E = intensity * window / d^2 (point, spot) or
// E = illuminance (directional), and a surface sends back E * (n.l) * pi * f(l, v), f the BRDF.
// The pi folded in keeps a white Lambert surface at E head-on, as before materials.
layout(constant_id = 0) const uint MATERIAL_FEATURES = 0xFFFFFFFFu;

const float PI = 3.14159265358979;
// Cook-Torrance: roughness below this is drawn as this (Filament's clamp): a smaller GGX lobe
// is narrower than a pixel and its peak overflows half floats
const float MIN_ROUGHNESS = 0.045;

vec3 schlick(vec3 f0, float cosine) {
    float w = 1.0 - clamp(cosine, 0.0, 1.0);  // pow of a negative 1 - cos, from rounding, is NaN
    return f0 + (1.0 - f0) * (w * w * w * w * w);
}

// The shading models some material of the scene uses (the low bits of MATERIAL_FEATURES)
const uint MODELS = MATERIAL_FEATURES & 0x3Fu;

// Whether `model` is `which`: false when no material uses it, true without a look at `model`
// when it is the only one used (the seed scenes' default palette: Blinn-Phong alone).
bool model_is(uint model, uint which) {
    return (MODELS & (1u << which)) != 0u && (MODELS == (1u << which) || model == which);
}

// pi * BRDF for unit normal n, direction to the light l, direction to the eye v; nl = n.l > 0.
vec3 brdf_pi(Material m, uint model, vec3 n, vec3 l, vec3 v, float nl) {
    vec3 base = m.base_color.rgb;
    float nv = clamp(dot(n, v), 0.0, 1.0);
    if (model_is(model, MODEL_OREN_NAYAR)) {
        // the qualitative model in vector form: s / t = cos(phi_i - phi_r) sin(alpha) tan(beta)
        float s2 = m.surface.y * m.surface.y;
        float a = 1.0 - 0.5 * s2 / (s2 + 0.33);
        float b = 0.45 * s2 / (s2 + 0.09);
        float s = dot(l, v) - nl * nv;
        float t = s > 0.0 ? max(nl, nv) : 1.0;
        return base * (a + b * max(s, 0.0) / t);
    }
    if (model_is(model, MODEL_PHONG)) {
        float e = m.surface.z;
        float rv = max(dot(reflect(-l, n), v), 0.0);
        return base + vec3(m.surface.w * pow(rv, e));   // w: strength * (e + 2) / 2 (materials.py)
    }
    if (model_is(model, MODEL_BLINN_PHONG)) {
        float e = m.surface.z;
        vec3 h = l + v;
        float h2 = dot(h, h);
        float nh = h2 > 1e-24 ? max(dot(n, h * inversesqrt(h2)), 0.0) : 0.0;
        return base + vec3(m.surface.w * pow(nh, e));   // w: strength * (e + 8) / 8
    }
    if (model_is(model, MODEL_COOK_TORRANCE)) {
        float metallic = m.surface.x;
        float r = max(m.surface.y, MIN_ROUGHNESS);
        float a2 = r * r * r * r;  // alpha = roughness^2
        vec3 h = l + v;
        float h2 = dot(h, h);
        h = h2 > 1e-24 ? h * inversesqrt(h2) : n;
        float nh = max(dot(n, h), 0.0);
        float vh = dot(v, h);
        float q = nh * nh * (a2 - 1.0) + 1.0;
        float d = a2 / (PI * q * q);
        float nv_ = max(nv, 1e-4);
        float vis = 0.5 / (nl * sqrt(nv_ * nv_ * (1.0 - a2) + a2) + nv_ * sqrt(nl * nl * (1.0 - a2) + a2));
        vec3 f0 = mix(vec3(0.04), base, metallic);
        vec3 f = schlick(f0, vh);
        // the diffuse lobe gets what the specular one leaves at this view: 1 - F(n.v). glTF's
        // sample mix, 1 - F(v.h) per light, reflects up to 30% more than it receives at grazing
        // views (a white dielectric of roughness 0.3 seen at 85 degrees: albedo 1.30, integrated
        // in NumPy); this one stays within 0.1% (tests/test_shading_models.py)
        return (1.0 - schlick(f0, nv)) * (1.0 - metallic) * base + PI * d * vis * f;
    }
    return base;  // lambert
}

// The light's E at `p` and the unit direction towards it (`l`); E = 0 when out of reach.
// Only the kinds the scene has are read (FEATURE_SPOT_LIGHTS, FEATURE_DIRECTIONAL_LIGHTS): with
// point lights alone a light is its first 32 bytes, as before spot and directional lights.
float light_at(Light light, vec3 p, vec3 fallback, out vec3 l) {
    const bool spots = (MATERIAL_FEATURES & FEATURE_SPOT_LIGHTS) != 0u;
    const bool suns = (MATERIAL_FEATURES & FEATURE_DIRECTIONAL_LIGHTS) != 0u;
    uint kind = spots || suns ? uint(light.direction_kind.w) : LIGHT_POINT;
    if (suns && kind == LIGHT_DIRECTIONAL) {
        l = -light.direction_kind.xyz;
        return light.color_intensity.w;
    }
    vec3 to_light = light.position_radius.xyz - p;
    float d2 = dot(to_light, to_light);
    float r = light.position_radius.w;
    float window = 1.0;
    if (r > 0.0) {
        float q = d2 / (r * r);
        window = clamp(1.0 - q * q, 0.0, 1.0);
        window *= window;
    }
    l = d2 > 1e-24 ? to_light * inversesqrt(d2) : fallback;
    float energy = light.color_intensity.w * window / max(d2, 1e-4);
    if (spots && kind == LIGHT_SPOT) {
        float t = clamp((dot(light.direction_kind.xyz, -l) - light.cone.x) * light.cone.y, 0.0, 1.0);
        energy *= t * t;
    }
    // capped: thousands of bright lights stay finite
    return min(energy, 65504.0);
}

// A view's map fills the first info.z texels of its layer across (render/shadow_pass.py draws
// it at its light's resolution; depth_model.w = that / the layer's): a point of the view's map
// ([0, 1]) on its layer, kept half a texel inside the map, where the sampler's clamp to the
// edge would have read the edge's texels.
vec2 shadow_uv(ShadowView v, vec2 uv) {
    float inside = 0.5 / float(v.info.z);
    return clamp(uv, vec2(inside), vec2(1.0 - inside)) * v.depth_model.w;
}

// One comparison of the receiver's depth `ref` at `uv` of a shadow map layer: 1 lit, 0 shadowed.
// Explicit (zero) gradients: legal in compute shaders and in non-uniform control flow.
float shadow_tap(bool hard, vec2 uv, float layer, float ref) {
    vec4 at = vec4(uv, layer, ref);
    return hard ? textureGrad(shadow_map_hard, at, vec2(0.0), vec2(0.0))
                : textureGrad(shadow_map, at, vec2(0.0), vec2(0.0));
}

// A depth of view v back to a distance from the light (along its axis): depth = P22 * z + P23
// orthographic (z = -distance), P22 + P23 / distance perspective (SHADOW_VIEW.depth_model).
float light_distance(ShadowView v, float depth) {
    return v.info.w == 0u ? (v.depth_model.y - depth) / v.depth_model.x
                          : v.depth_model.y / max(depth - v.depth_model.x, 1e-9);
}

// A disc of PCSS_TAPS points (Vogel's golden-angle spiral: even cover at any count). PCSS's
// search and filter turn it by a noise of the shadow map's texel position
// (Jimenez' interleaved gradient noise, at a quarter texel), so its few taps give a smooth penumbra
// with fine noise instead of the bands a fixed grid draws. The noise is fixed to the map, so it
// does not crawl when the camera moves (cascades move in whole texels).
const int PCSS_TAPS = 16;

// The first tap's offset: the noise's direction at radius sqrt(0.5 / 16), in map units of
// `texel`; each next tap turns by the golden angle (GOLDEN) and moves out to sqrt((i + 0.5) / 16).
// A recurrence: one sin and cos a pixel, no table. (A sin and cos per tap, then a constant
// table, each cost the PCF, spot and point frames 3-6% of GPU time on the H100.)
const mat2 GOLDEN = mat2(-0.73736888, 0.67549029, -0.67549029, -0.73736888);  // 2.39996323 rad
vec2 shadow_noise_direction(vec2 uv, float size, float texel) {
    vec2 at = floor(uv * size * 4.0);
    float angle = 6.28318531 * fract(52.9829189 * fract(dot(at, vec2(0.06711056, 0.00583715))));
    return vec2(cos(angle), sin(angle)) * texel;
}

// Percentage-closer soft shadows (R. Fernando, 2005): the average depth of the casters around
// the receiver (a disc of PCSS_SEARCH texels across) gives the penumbra by similar triangles,
// (receiver - blocker) * size / blocker for a spot or point light of size `softness`, (receiver
// - blocker) * softness for a directional one (its width per unit of distance); then PCF over a
// disc that wide: contact shadows stay sharp, far ones spread.
const float PCSS_SEARCH = 12.0;
const float PCSS_MAX = 24.0;  // the widest filter, in texels
float pcss(ShadowView v, vec2 uv, float layer, float ref, float depth) {
    vec2 first = shadow_noise_direction(uv, float(v.info.z), 1.0 / float(v.info.z));
    float sum = 0.0, found = 0.0;
    vec2 direction = first;
    for (int i = 0; i < PCSS_TAPS; ++i) {
        vec2 at = uv + direction * (sqrt((float(i) + 0.5) / float(PCSS_TAPS)) * PCSS_SEARCH);
        direction = GOLDEN * direction;
        float z = textureGrad(shadow_depth, vec3(shadow_uv(v, at), layer), vec2(0.0), vec2(0.0)).r;
        if (z > ref) {   // reverse-Z: nearer the light than the receiver
            sum += z;
            found += 1.0;
        }
    }
    if (found == 0.0) {
        return 1.0;
    }
    float receiver = light_distance(v, depth), blocker = light_distance(v, sum / found);
    float gap = max(receiver - blocker, 0.0);
    bool perspective = v.info.w != 0u;
    float penumbra = perspective ? gap * v.params.w / max(blocker, 1e-4) : gap * v.params.w;
    float texel_world = v.depth_model.z * (perspective ? receiver : 1.0);
    float radius = clamp(penumbra / max(texel_world, 1e-9), 1.0, PCSS_MAX);
    float lit = 0.0;
    direction = first;
    for (int i = 0; i < PCSS_TAPS; ++i) {
        vec2 at = uv + direction * (sqrt((float(i) + 0.5) / float(PCSS_TAPS)) * radius);
        lit += shadow_tap(false, shadow_uv(v, at), layer, ref);
        direction = GOLDEN * direction;
    }
    return lit / float(PCSS_TAPS);
}

// How much of light `light` reaches p (normal n) past its casters: 1 without shadows. A
// directional light's cascade is picked by p's view depth (past the last one nothing is
// shadowed), a point light's cube face by the direction from the light.
// The receiver is moved along its normal and its depth towards the light (Shadow.normal_offset,
// Shadow.bias); reverse-Z, so a receiver is lit where its depth is at least the map's.
float light_shadow(Light light, vec3 p, vec3 n) {
    uint named = uint(light.cone.w);
#ifdef RAY_SHADOW_MASK
    if ((MATERIAL_FEATURES & FEATURE_RAY_SHADOWS) != 0u) {
        // ray-traced: cone.w names the light's place in the mask (render/ray_shadows.py), which
        // only the deferred lighting has; forward surfaces (blended ones), and lights past the
        // traced ones, read the shadow maps drawn for them (cone.z)
        uint place = named / RAY_PLACE;
        if (place != 0u) {
            return ray_shadow_mask(place - 1u);
        }
    }
#endif
    uint first = uint(light.cone.z);
    if (first == 0u) {
        return 1.0;
    }
    first -= 1u;
    uint count = max(named % RAY_PLACE, 1u);
    uint k = 0u;
    if (shadow_views[first].info.w == 2u) {
        // a point light's cube: the face of the major axis of the direction from the light
        // (the cube map face selection; render/shadow_views.py's CUBE_FACES order)
        vec3 r = p - light.position_radius.xyz;
        vec3 a = abs(r);
        uint axis = a.x >= a.y && a.x >= a.z ? 0u : (a.y >= a.z ? 1u : 2u);
        k = 2u * axis + (r[axis] < 0.0 ? 1u : 0u);
    } else if (count > 1u || shadow_views[first].info.w == 0u) {
        float depth = -(g.view * vec4(p, 1.0)).z;
        if (depth > shadow_views[first + count - 1u].params.z) {
            return 1.0;
        }
        while (k + 1u < count && depth > shadow_views[first + k].params.z) {
            ++k;
        }
    }
    ShadowView v = shadow_views[first + k];
    bool perspective = v.info.w != 0u;
    float w0 = perspective ? max((v.view_projection * vec4(p, 1.0)).w, 0.0) : 1.0;
    vec4 c = v.view_projection * vec4(p + n * (v.params.y * w0), 1.0);
    if (c.w <= 0.0) {
        return 1.0;
    }
    vec3 ndc = c.xyz / c.w;
    vec2 uv = ndc.xy * 0.5 + 0.5;
    if (any(lessThan(uv, vec2(0.0))) || any(greaterThan(uv, vec2(1.0))) || ndc.z < 0.0 || ndc.z > 1.0) {
        return 1.0;
    }
    float ref = ndc.z + (perspective ? v.params.x / c.w : v.params.x);
    float layer = float(v.info.x);
    if (v.info.y == SHADOW_HARD) {
        return shadow_tap(true, shadow_uv(v, uv), layer, ref);
    }
    if (v.info.y == SHADOW_PCSS) {
        return pcss(v, uv, layer, ref, ndc.z);
    }
    // PCF: 3 x 3 taps `softness` texels apart, each a bilinear 2 x 2 comparison
    vec2 step = vec2(v.params.w / float(v.info.z));
    float lit = 0.0;
    for (int y = -1; y <= 1; ++y) {
        for (int x = -1; x <= 1; ++x) {
            lit += shadow_tap(false, shadow_uv(v, uv + vec2(x, y) * step), layer, ref);
        }
    }
    return lit / 9.0;
}

// The unit direction from p towards the eye, which every view-dependent term takes (specular,
// Fresnel, Oren-Nayar, the environment's reflections): towards the camera's position in a
// perspective view; in an orthographic one (P33 = 1, as sky.frag tells them apart) every ray is
// parallel, so it is the camera's +Z (the view's third row) wherever p is: there the camera's
// position only places the near plane, and moving the camera along its axis changes nothing seen.
vec3 eye_direction(vec3 p) {
    if (g.projection[3][3] == 1.0) {
        return normalize(vec3(g.view[0][2], g.view[1][2], g.view[2][2]));
    }
    vec3 eye = g.eye.xyz - p;
    float e2 = dot(eye, eye);
    return e2 > 1e-24 ? eye * inversesqrt(e2) : vec3(0.0, 0.0, 1.0);
}

// What light i adds at p (normal n, unit direction to the eye to_eye: eye_direction) under the material's
// model; `shadowed`: p receives shadows (a mesh without NotShadowReceiver).
vec3 light_term(uint i, Material m, uint model, vec3 p, vec3 n, vec3 to_eye, bool shadowed) {
    Light light = lights[i];
    vec3 l;
    float energy = light_at(light, p, n, l);
    float nl = dot(n, l);
    if (nl > 0.0 && energy > 0.0) {
        if ((MATERIAL_FEATURES & FEATURE_SHADOWS) != 0u && shadowed) {
            energy *= light_shadow(light, p, n);
        }
        return light.color_intensity.rgb * (energy * nl) * brdf_pi(m, model, n, l, to_eye, nl);
    }
    return vec3(0.0);
}

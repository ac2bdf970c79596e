// The world's Environment (render/environment.py) in the surfaces, after shading.glsl. Compiled
// in only with FEATURE_ENVIRONMENT (a world without one reads none of it). Directions are in the
// world's axes (positions are render-relative, not rotated), as the cube map's faces are.

// Radiance from direction d, blurred to mip level `lod` (0: sharp; level roughness * g.environment.y
// holds the GGX lobe of that roughness, environment_prefilter.py), times the intensity.
vec3 environment_radiance(vec3 d, float lod) {
    return textureLod(environment_map, d, lod).rgb * g.environment.x;
}

// What a white Lambertian surface facing n reflects of the environment: its 9 spherical
// harmonics (environment_maps.irradiance_sh9, the same basis and order), times the intensity.
vec3 environment_irradiance(vec3 n) {
    vec3 e = g.irradiance[0].rgb * 0.282095
        + g.irradiance[1].rgb * (0.488603 * n.y)
        + g.irradiance[2].rgb * (0.488603 * n.z)
        + g.irradiance[3].rgb * (0.488603 * n.x)
        + g.irradiance[4].rgb * (1.092548 * n.x * n.y)
        + g.irradiance[5].rgb * (1.092548 * n.y * n.z)
        + g.irradiance[6].rgb * (0.315392 * (3.0 * n.z * n.z - 1.0))
        + g.irradiance[7].rgb * (1.092548 * n.x * n.z)
        + g.irradiance[8].rgb * (0.546274 * (n.x * n.x - n.y * n.y));
    return max(e, vec3(0.0)) * g.environment.x;
}

// The split-sum's environment BRDF (scale, bias of F0), B. Karis' analytic fit ("Physically based
// shading on mobile", 2014): no lookup texture.
vec2 environment_brdf(float nv, float roughness) {
    const vec4 c0 = vec4(-1.0, -0.0275, -0.572, 0.022);
    const vec4 c1 = vec4(1.0, 0.0425, 1.04, -0.04);
    vec4 r = roughness * c0 + c1;
    float a004 = min(r.x * r.x, exp2(-9.28 * nv)) * r.x + r.y;
    return vec2(-1.04, 1.04) * a004 + r.zw;
}

// The ambient light from the environment (replaces the flat ambient when g.environment.z is 1):
// diffuse from the harmonics; for Cook-Torrance also the specular (Karis' split sum): the
// GGX-prefiltered mip chain read at the surface's roughness, times the environment BRDF.
vec3 environment_ambient(Material m, uint model, vec3 n, vec3 v, float occlusion) {
    vec3 base = m.base_color.rgb;
    if (model_is(model, MODEL_COOK_TORRANCE)) {
        float metallic = m.surface.x, roughness = m.surface.y;
        float nv = clamp(dot(n, v), 0.0, 1.0);
        vec3 f0 = mix(vec3(0.04), base, metallic);
        vec2 ab = environment_brdf(nv, roughness);
        vec3 specular = environment_radiance(reflect(-v, n), roughness * g.environment.y) * (f0 * ab.x + ab.y);
        return (base * (1.0 - metallic) * environment_irradiance(n) + specular) * occlusion;
    }
    return base * environment_irradiance(n) * occlusion;
}

// A mirroring material's surface (Material.reflectivity, refraction, ior): the lit colour mixed
// with the refracted environment (glass: mixed with its reflection by Fresnel, F0 from ior), then
// with the reflected one (Schlick's Fresnel with F0 = reflectivity). Blurred by roughness.
vec3 environment_surface(vec3 color, Material m, vec3 n, vec3 v) {
    float reflectivity = m.environment.x, refraction = m.environment.y, ior = m.environment.z;
    if (reflectivity <= 0.0 && refraction <= 0.0) {
        return color;
    }
    float lod = m.surface.y * g.environment.y;
    vec3 reflected = environment_radiance(reflect(-v, n), lod);
    float w = 1.0 - clamp(dot(n, v), 0.0, 1.0);
    float grazing = w * w * w * w * w;
    if (refraction > 0.0) {
        float f0 = (ior - 1.0) / (ior + 1.0);
        f0 *= f0;
        vec3 t = refract(-v, n, 1.0 / ior);   // zero on total internal reflection: all reflected
        float fresnel = dot(t, t) > 0.0 ? f0 + (1.0 - f0) * grazing : 1.0;
        vec3 glass = mix(environment_radiance(t, lod), reflected, fresnel);
        color = mix(color, glass, refraction);
    }
    if (reflectivity > 0.0) {
        color = mix(color, reflected, reflectivity + (1.0 - reflectivity) * grazing);
    }
    return color;
}

// Clustered lights (render/light_clusters.py), shared by the passes that build the light grid and
// the fragments that read it. A cluster is a screen tile times a distance bin: an exponential
// shell around the eye. Each bin holds the lowest and highest index of a light reaching into it
// (the lights are sorted by distance, so the range is tight); each tile a bit mask of the lights
// whose bounding sphere touches its frustum. A fragment walks the mask words of its bin's range.

// The distance bin of a distance from the eye (the first bin also takes what is nearer than s,
// the last what is beyond the farthest bounded light).
uint light_bin(float distance) {
    return min(uint(log(max(distance, g.bin_depth.x) / g.bin_depth.x) * g.bin_depth.y), uint(LIGHT_BINS - 1));
}

// A bounded light's sphere (centre relative to the render origin, radius): a point light's own; a
// spot light's cone bounded more tightly (B. Wronski, "Cull that cone"): for a half angle up to
// 45 degrees the sphere through the apex and the cap's rim, else the one around the cap.
vec4 light_sphere(Light light) {
    vec3 p = light.position_radius.xyz;
    float r = light.position_radius.w;
    float c = light.cone.x;   // cos(outer); points: below -1
    if (uint(light.direction_kind.w) != LIGHT_SPOT || c <= 0.0) {
        return vec4(p, r);
    }
    vec3 axis = light.direction_kind.xyz;
    if (c >= 0.70710678) {
        float half_length = r / (2.0 * c);
        return vec4(p + axis * half_length, half_length);
    }
    return vec4(p + axis * (r * c), r * sqrt(max(1.0 - c * c, 0.0)));
}

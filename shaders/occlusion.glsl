// Two-phase occlusion culling's set (2) and tests (render/occlusion.py), after niagara
// (zeux/niagara: drawcull.comp, math.h). Needs common.glsl (g: the camera's globals) and a push
// block `pc` of type CullPush.
// row_visible: per instance row, 1 where the last frame's late pass found it visible (the early
// pass draws those rows' depth). pyramid: the early depth's min-reduction (reverse-Z: min is the
// farthest), level k at ceil(size / 2^(k+1)) texels, levels one after the other; a texel at level
// k covers the depth pixels [x, x + 1) * 2^(k+1) (clamped to the image), so every test is exact
// about which pixels it looks at.
#ifdef VISIBILITY_WRITABLE
layout(std430, set = SET_OCCLUSION, binding = BINDING_VISIBILITY) writeonly buffer Visibility { uint row_visible[]; };
#else
layout(std430, set = SET_OCCLUSION, binding = BINDING_VISIBILITY) readonly buffer Visibility { uint row_visible[]; };
#endif
layout(std430, set = SET_OCCLUSION, binding = BINDING_PYRAMID) readonly buffer Pyramid { float pyramid[]; };

// The first float of pyramid level k and its size.
uint pyramid_level(uint k, out uvec2 size) {
    uvec2 s = (pc.occlusion.xy + 1u) >> 1;
    uint first = 0u;
    for (uint l = 0u; l < k; ++l) {
        first += s.x * s.y;
        s = (s + 1u) >> 1;
    }
    size = s;
    return first;
}

// The sphere (view space: the camera looks down -z) in normalised device coordinates: a rect
// (x0, y0, x1, y1) that holds its projection, and the depth of its nearest point (reverse-Z:
// larger is nearer). False when it reaches the near plane: then it is not tested.
// 2D Polyhedral Bounds of a Clipped, Perspective-Projected 3D Sphere (Mara, McGuire 2013), as
// niagara's projectSphere, with the off-axis terms of region_projection (maths/camera.py).
bool project_sphere(vec3 c, float r, out vec4 rect, out float nearest) {
    mat4 P = g.projection;  // [column][row]
    float zn = c.z + r;
    float wn = P[2][3] * zn + P[3][3];
    if (wn <= 0.0) return false;
    nearest = (P[2][2] * zn + P[3][2]) / wn;
    if (nearest >= 1.0) return false;
    if (P[2][3] != 0.0) {  // perspective: clip w = -z
        float d = -c.z;
        float dr2 = d * d - r * r;  // > 0: the nearest point is past the near plane
        float vx = sqrt(c.x * c.x + dr2);
        float vy = sqrt(c.y * c.y + dr2);
        vec2 tx = vec2((vx * c.x - d * r) / (vx * d + c.x * r), (vx * c.x + d * r) / (vx * d - c.x * r));
        vec2 ty = vec2((vy * c.y - d * r) / (vy * d + c.y * r), (vy * c.y + d * r) / (vy * d - c.y * r));
        vec2 x = P[0][0] * tx - P[2][0];  // x / w with z / w = -1
        vec2 y = P[1][1] * ty - P[2][1];
        rect = vec4(min(x.x, x.y), min(y.x, y.y), max(x.x, x.y), max(y.x, y.y));
    } else {  // orthographic: clip w = 1
        vec2 mid = vec2(P[0][0] * c.x + P[2][0] * c.z + P[3][0], P[1][1] * c.y + P[2][1] * c.z + P[3][1]);
        vec2 half_size = abs(vec2(P[0][0], P[1][1])) * r;
        rect = vec4(mid - half_size, mid + half_size);
    }
    return true;
}

// Whether the sphere may show: false when it covers no pixel centre (CULL_SUBPIXEL) or lies
// behind the farthest early depth over every pixel it covers.
bool occlusion_visible(vec3 center, float radius) {
    vec3 c = (g.view * vec4(center, 1.0)).xyz;
    vec4 rect;
    float nearest;
    // a little larger: the rasteriser's depth and the sphere's are not worked out alike
    if (!project_sphere(c, radius * 1.01, rect, nearest)) return true;
    vec2 size = vec2(pc.occlusion.xy);
    vec4 px = clamp((rect * 0.5 + 0.5) * size.xyxy, vec4(-2.0), size.xyxy + 2.0);
    ivec4 p;
    if ((pc.occlusion.w & CULL_SUBPIXEL) != 0u) {
        // the pixel centres inside, with a margin of 1/16 pixel: Vulkan snaps vertices to at
        // least 4 sub-pixel bits (1/32 pixel of error at most)
        p = ivec4(ceil(px.xy - 0.5625), floor(px.zw - 0.4375));
        if (p.x > p.z || p.y > p.w) return false;
    } else {
        p = ivec4(floor(px));
    }
    p = clamp(p, ivec4(0), ivec4(pc.occlusion.xyxy) - 1);
    if (p.x > p.z || p.y > p.w) return false;  // off the target
    uint k = 0u;
    while (k + 1u < pc.occlusion.z && (((p.z >> (k + 1u)) - (p.x >> (k + 1u))) > 1 || ((p.w >> (k + 1u)) - (p.y >> (k + 1u))) > 1)) ++k;
    uvec2 level_size;
    uint first = pyramid_level(k, level_size);
    uvec4 t = uvec4(p) >> (k + 1u);
    float farthest = min(min(pyramid[first + t.y * level_size.x + t.x], pyramid[first + t.y * level_size.x + t.z]),
                         min(pyramid[first + t.w * level_size.x + t.x], pyramid[first + t.w * level_size.x + t.z]));
    return nearest >= farthest;
}

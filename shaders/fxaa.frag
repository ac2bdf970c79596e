#version 450

// FXAA 3.11, PC quality (Timothy Lottes, NVIDIA, 2011), preset 39 ("extreme": 12 search steps,
// the first five of one texel, so no dithering along long, nearly axis-aligned edges), as a
// full-screen pass on the tone-mapped (display-referred) image. Luma is computed here from the
// colour (Rec. 601 weights on the display-encoded value), not read from alpha. See
// ecs_engine/render/post/fxaa.py for the steps; tests/fxaa_reference.py is the same in NumPy.

layout(set = 0, binding = 0) uniform sampler2D source;  // bilinear, clamp to edge, LOD 0

layout(push_constant) uniform Push {
    float subpix;              // amount of sub-pixel aliasing removal, 0 (off) to 1 (softest)
    float edge_threshold;      // local contrast needed, relative to the brightest neighbour
    float edge_threshold_min;  // ... and at least this, so dark areas are left alone
    ivec2 offset;              // where the output starts in the target (a camera view's rectangle)
} push;

// The source is an _SRGB image: sampling decodes it to linear colour, whose luma is brought
// back to a perceptual scale by a square root (FXAA's edge tests assume perceptual luma).
layout(constant_id = 0) const bool LINEAR_SOURCE = false;

layout(location = 0) out vec4 out_color;

const int STEPS = 12;
const float STEP[STEPS] = float[](1.0, 1.0, 1.0, 1.0, 1.0, 1.5, 2.0, 2.0, 2.0, 2.0, 4.0, 8.0);

float luma(vec3 c) {
    float y = dot(c, vec3(0.299, 0.587, 0.114));
    return LINEAR_SOURCE ? sqrt(y) : y;
}

// The 3x3 neighbourhood by texel, clamped to the edge as the sampler clamps: exact values, so a
// flat region's early exit writes back exactly what it read.
vec4 texel(ivec2 p, ivec2 size) {
    return texelFetch(source, clamp(p, ivec2(0), size - 1), 0);
}

float luma_at(vec2 uv) {
    return luma(textureLod(source, uv, 0.0).rgb);
}

void main() {
    ivec2 size = textureSize(source, 0);
    vec2 rcp = 1.0 / vec2(size);
    ivec2 p = ivec2(gl_FragCoord.xy) - push.offset;
    vec2 posM = (vec2(p) + 0.5) * rcp;

    vec4 rgbaM = texel(p, size);
    float lumaM = luma(rgbaM.rgb);
    float lumaN = luma(texel(p + ivec2(0, -1), size).rgb);
    float lumaS = luma(texel(p + ivec2(0, 1), size).rgb);
    float lumaE = luma(texel(p + ivec2(1, 0), size).rgb);
    float lumaW = luma(texel(p + ivec2(-1, 0), size).rgb);

    // Too little local contrast: no edge here, the pixel passes unchanged.
    float rangeMax = max(max(max(lumaN, lumaW), max(lumaE, lumaS)), lumaM);
    float rangeMin = min(min(min(lumaN, lumaW), min(lumaE, lumaS)), lumaM);
    float range = rangeMax - rangeMin;
    if (range < max(push.edge_threshold_min, rangeMax * push.edge_threshold)) {
        out_color = rgbaM;
        return;
    }

    float lumaNW = luma(texel(p + ivec2(-1, -1), size).rgb);
    float lumaNE = luma(texel(p + ivec2(1, -1), size).rgb);
    float lumaSW = luma(texel(p + ivec2(-1, 1), size).rgb);
    float lumaSE = luma(texel(p + ivec2(1, 1), size).rgb);

    // Sub-pixel aliasing: how far the centre stands out of its 3x3 low-pass, by the range.
    float lumaNS = lumaN + lumaS;
    float lumaWE = lumaW + lumaE;
    float lumaNESE = lumaNE + lumaSE;
    float lumaNWSW = lumaNW + lumaSW;
    float subpixA = (lumaNS + lumaWE) * 2.0 + lumaNWSW + lumaNESE;
    float subpixC = clamp(abs(subpixA * (1.0 / 12.0) - lumaM) / range, 0.0, 1.0);
    float subpixF = (-2.0 * subpixC + 3.0) * subpixC * subpixC;
    float subpixH = subpixF * subpixF * push.subpix;

    // Edge orientation: second differences across rows against across columns.
    float edgeHorz = abs(-2.0 * lumaW + lumaNWSW) + abs(-2.0 * lumaM + lumaNS) * 2.0 + abs(-2.0 * lumaE + lumaNESE);
    float edgeVert = abs(-2.0 * lumaS + lumaSW + lumaSE) + abs(-2.0 * lumaM + lumaWE) * 2.0
        + abs(-2.0 * lumaN + lumaNW + lumaNE);
    bool horzSpan = edgeHorz >= edgeVert;
    float lengthSign = horzSpan ? rcp.y : rcp.x;
    if (!horzSpan) {
        lumaN = lumaW;
        lumaS = lumaE;
    }

    // The side of the centre the edge lies on: the neighbour across it with the larger step.
    float gradientN = lumaN - lumaM;
    float gradientS = lumaS - lumaM;
    bool pairN = abs(gradientN) >= abs(gradientS);
    float gradient = max(abs(gradientN), abs(gradientS));
    if (pairN) {
        lengthSign = -lengthSign;
    }
    float lumaNN = (pairN ? lumaN : lumaS) + lumaM;
    float gradientScaled = gradient * 0.25;
    bool lumaMLTZero = lumaM - lumaNN * 0.5 < 0.0;

    // Walk along the edge (on the line between the two pixels) both ways until the average
    // luma there leaves the pair's mean by a quarter of the gradient: the edge's two ends.
    vec2 posB = posM;
    vec2 offNP = horzSpan ? vec2(rcp.x, 0.0) : vec2(0.0, rcp.y);
    if (horzSpan) {
        posB.y += lengthSign * 0.5;
    } else {
        posB.x += lengthSign * 0.5;
    }
    vec2 posN = posB - offNP * STEP[0];
    vec2 posP = posB + offNP * STEP[0];
    float lumaEndN = luma_at(posN) - lumaNN * 0.5;
    float lumaEndP = luma_at(posP) - lumaNN * 0.5;
    bool doneN = abs(lumaEndN) >= gradientScaled;
    bool doneP = abs(lumaEndP) >= gradientScaled;
    if (!doneN) posN -= offNP * STEP[1];
    if (!doneP) posP += offNP * STEP[1];
    for (int i = 2; i < STEPS && !(doneN && doneP); ++i) {
        if (!doneN) lumaEndN = luma_at(posN) - lumaNN * 0.5;
        if (!doneP) lumaEndP = luma_at(posP) - lumaNN * 0.5;
        doneN = abs(lumaEndN) >= gradientScaled;
        doneP = abs(lumaEndP) >= gradientScaled;
        if (!doneN) posN -= offNP * STEP[i];
        if (!doneP) posP += offNP * STEP[i];
    }

    // Blend toward the pixel across the edge by how near the closer end is (a staircase's step
    // is blended most at its ends), if the edge ends the right way there; at least the
    // sub-pixel amount.
    float dstN = horzSpan ? posM.x - posN.x : posM.y - posN.y;
    float dstP = horzSpan ? posP.x - posM.x : posP.y - posM.y;
    bool directionN = dstN < dstP;
    bool goodSpan = directionN ? (lumaEndN < 0.0) != lumaMLTZero : (lumaEndP < 0.0) != lumaMLTZero;
    float pixelOffset = 0.5 - min(dstN, dstP) / (dstN + dstP);
    float offset = max(goodSpan ? pixelOffset : 0.0, subpixH);
    if (horzSpan) {
        posM.y += offset * lengthSign;
    } else {
        posM.x += offset * lengthSign;
    }
    out_color = vec4(textureLod(source, posM, 0.0).rgb, rgbaM.a);
}

#version 450
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_samplerless_texture_functions : require
#include "layouts.glsl"

// The HDR colour of this pixel (a sampled image read with texelFetch: the same pixel, no
// filtering, as the input attachment it once was), scaled by the exposure and mapped into [0, 1]
// by the operator; the sRGB target encodes it on write.
layout(set = 0, binding = 0) uniform texture2D hdr;
// `offset`: where the view's rectangle starts in the target (split screen: render/frame/view_graph.py);
// the HDR colour is the view's own, drawn from its corner, so the pixel read is shifted back
layout(push_constant) uniform Push {
    ToneMapPush push;
    ivec2 offset;
};

layout(location = 0) out vec4 out_color;

// Narkowicz's fit of the ACES filmic curve (2015), per channel
vec3 aces(vec3 x) {
    return clamp((x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14), 0.0, 1.0);
}

void main() {
    vec3 c = max(texelFetch(hdr, ivec2(gl_FragCoord.xy) - offset, 0).rgb, vec3(0.0)) * push.exposure;
    if (push.operator == TONE_MAP_ACES) {
        c = aces(c);
    } else if (push.operator == TONE_MAP_REINHARD) {
        c = c / (1.0 + c);
    } else {
        c = min(c, vec3(1.0));
    }
    out_color = vec4(c, 1.0);
}

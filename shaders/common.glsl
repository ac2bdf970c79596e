// Shared declarations. Matrices come from NumPy [row, col] arrays uploaded transposed, so they
// arrive column-major as GLSL expects. Positions are relative to the render origin, which is the
// camera unless RenderOrigin is pinned (then g.eye says where the camera is).
layout(set = 0, binding = 0) uniform Globals {
    mat4 projection;    // reverse-Z: near -> depth 1, far/infinity -> 0
    mat4 view;          // rotation, and the translation from the render origin to the camera
                        // (zero when rendering camera-relative, the default)
    vec4 eye;           // xyz: the camera relative to the render origin (zero by default)
    vec4 ambient;       // rgb, intensity
    uvec4 counts;       // x: number of lights
} g;

struct Light {
    vec4 position_radius;   // camera-relative position, radius (0: unbounded)
    vec4 color_intensity;   // linear rgb, intensity
};
layout(std430, set = 0, binding = 1) readonly buffer Lights { Light lights[]; };

struct Instance {           // 64 bytes: model matrix rows, material (the normal matrix is derived)
    vec4 m0, m1, m2;        // rows of the camera-relative model matrix (last row is 0 0 0 1)
    uvec4 misc;             // x: material index, y: key = mesh * 2 + mirrored
};
layout(std430, set = 0, binding = 2) readonly buffer Instances { Instance instances[]; };

struct Material {
    vec4 color;             // linear rgb, unused
    vec4 specular;          // strength, shininess, unused, unused
};
layout(std430, set = 0, binding = 3) readonly buffer Materials { Material materials[]; };

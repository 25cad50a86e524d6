#version 330
// arbvis (new): the precise splats' vertex stage: splat.vert (the seed's size rule,
// per-point Phong) plus what precise.frag needs to compute each fragment's footprint from
// gl_FragCoord rather than gl_PointCoord (llvmpipe's sprite coordinate is ~2e-3 px off
// the window position, which moves a Gaussian's rim pixels by up to 0.2): the splat's
// window position and its size clamped to the size range, in v_window. gl_PointSize is
// that size plus a margin, so the rasterizer's square (snapped to its fixed point)
// holds every pixel whose centre lies in the exact square; precise.frag decides coverage.
// Same locals as splat.vert, plus [9]: the viewport (x, y, width, height) in window
// coordinates; [10]: (smallest size, largest size, margin, 0). The size and the window
// position are computed with the ARB twin's operations (RSQ of a selected squared
// distance, a reciprocal of w), so the twins place splats alike to the bit.
// ARB twin: precise.arbvp.
layout(location = 0) in vec3 aPos;
layout(location = 1) in vec3 aColor;
layout(location = 2) in float aValue;
layout(location = 3) in vec3 aNormal;
// A COPC point's size over the deepest drawn level's (1 for other clouds): coarse points
// cover for the children not drawn.
layout(location = 4) in float aScale;
uniform vec4 vertex_local[11];
out vec3 v_color;
out float v_value;
out vec2 v_light;
out float v_z;
flat out vec3 v_window;
void main() {
    vec4 p = vec4(aPos, 1.0);
    vec4 clip = vec4(dot(vertex_local[0], p), dot(vertex_local[1], p),
                     dot(vertex_local[2], p), dot(vertex_local[3], p));
    gl_Position = clip;
    bool perspective = vertex_local[4].w > 0.5;
    vec3 cameraPos = vertex_local[4].xyz;
    float pointSize = vertex_local[6].x;
    float factor = vertex_local[6].y;
    // The squared distance to the eye in perspective, 1 in orthographic, selected as
    // the ARB twin selects it (exact for distances over 0.71, the eye's units).
    vec3 d = aPos - cameraPos;
    float dd = (perspective ? 1.0 : 0.0) * (dot(d, d) - 1.0) + 1.0;
    float size = pointSize * inversesqrt(dd) * factor * aScale;
    // GL clamps gl_PointSize to its range; a NaN size stays NaN (nothing is drawn).
    if (!isnan(size)) size = clamp(size, vertex_local[10].x, vertex_local[10].y);
    gl_PointSize = size + vertex_local[10].z;
    vec2 ndc = clip.xy * (1.0 / clip.w);
    // A point whose centre lies outside the clip volume is dropped whole, as the GL spec
    // and the f64 reference drop it: some drivers (NVIDIA) draw wide points whose centre
    // is off-screen. A size of 0 makes precise.frag discard every fragment.
    float inside = (clip.w > 0.0 && all(lessThanEqual(abs(clip.xyz), vec3(clip.w)))) ? 1.0 : 0.0;
    v_window = vec3((ndc + 1.0) * 0.5 * vertex_local[9].zw + vertex_local[9].xy, size * inside);
    v_color = aColor;
    v_value = aValue;
    v_z = dot(vertex_local[8], p);
    v_light = vec2(1.0, 0.0);
    if (vertex_local[6].z > 0.5) {
        vec3 v = normalize(perspective ? cameraPos - aPos : -vertex_local[5].xyz);
        vec3 n = aNormal;
        if (dot(n, v) < 0.0) n = -n;
        float diffuse = max(dot(n, v), 0.0);
        vec3 r = 2.0 * dot(n, v) * n - v;
        float specular = pow(max(dot(r, v), 0.0), vertex_local[7].w);
        v_light = vec2(vertex_local[7].x + vertex_local[7].y * diffuse,
                       vertex_local[7].z * specular);
    }
}

#version 330
// arbvis (new): seed 004's fragment shader corrected: the property normalized as
// (value - min) / (max - min), clamped, 0 for an empty range; the footprints fall off
// from the centre (smoothstep(0, 1, 1 - n_dist), exp(-n_dist^2 / (2 width)), a width of 0
// giving a single opaque pixel at the centre). Uniforms as seed.frag. ARB twin: precise.arbfp.
// The footprint is taken from gl_FragCoord and the splat's window position and size
// (v_window, from precise.vert), not from gl_PointCoord: the pixel centre must lie in the
// half-open square of side `size` around the position (the rasterizer's square, which
// precise.vert widens, is only a superset) and n_dist = |d| (1 / (size / 2)), the f64
// reference's |d| / (size / 2) with the ARB twin's reciprocal.
uniform vec4 program_local[6];
in vec3 v_color;
in float v_value;
in vec2 v_light;
in float v_z;
flat in vec3 v_window;
out vec4 FragColor;
const float PI = 3.14159265358979;

float normalized(float value, float min_value, float max_value) {
    if (!(max_value > min_value) || isnan(value)) return 0.0;
    return clamp((value - min_value) / (max_value - min_value), 0.0, 1.0);
}

void main() {
    vec2 d = gl_FragCoord.xy - v_window.xy;
    float half_size = 0.5 * v_window.z;
    if (any(lessThan(d, vec2(-half_size))) || any(greaterThanEqual(d, vec2(half_size))))
        discard;
    float n_dist = length(d) * (1.0 / half_size);
    if (!(n_dist <= 1.0)) discard;
    float min_value = program_local[0].y;
    float max_value = program_local[0].z;
    float n = normalized(v_value, min_value, max_value);
    vec3 color = v_color;
    if (program_local[0].x > 0.5) {
        vec3 pct = vec3(smoothstep(0.0, 1.0, n), sin(n * PI), sqrt(n));
        color = mix(program_local[1].rgb, program_local[2].rgb, pct);
    }
    color = color * v_light.x + v_light.y;
    float alpha;
    if (program_local[3].x > 0.5) {
        float w = program_local[3].y;
        alpha = w > 0.0 ? exp(-n_dist * n_dist / (2.0 * w)) : (n_dist == 0.0 ? 1.0 : 0.0);
    } else {
        alpha = smoothstep(0.0, 1.0, 1.0 - n_dist);
    }
    if (program_local[0].w > 0.5) {
        float t = program_local[4].x;
        float r = program_local[4].y;
        alpha *= (v_value >= t - r && v_value <= t + r) ? smoothstep(0.0, 1.0, n) : 0.0;
    }
    alpha = clamp(alpha, 0.0, 1.0);
    // arbvis: program_local[5].x > 0.5 is weighted blended OIT's accumulation pass
    // (McGuire & Bavoil 2013, eq. 7 weight; splats::oit): (clamp(color) a w, a w).
    if (program_local[5].x > 0.5) {
        float z5 = v_z / 5.0;
        float z200 = v_z / 200.0;
        float z2 = z200 * z200;
        float w = alpha * clamp(10.0 / (1e-5 + z5 * z5 + z2 * z2 * z2), 1e-2, 3e3);
        FragColor = vec4(clamp(color, 0.0, 1.0) * alpha * w, alpha * w);
    } else {
        FragColor = vec4(color, alpha);
    }
}

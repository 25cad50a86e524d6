#version 330
// arbvis: seed 004's fragment shader functions as the text gives them (gradient_scale
// divides by the range without subtracting the minimum; gauss and smoothstep are taken
// of n_dist, so alpha is lowest at the splat's centre; TransferFunction's insideRange is
// `minView <= value <= maxView`, which the text leaves implicit), with arbvis's uniforms:
// program_local[0]: (colour from: 0 point colour / 1 gradient_scale, min, max, volume)
// [1]: colorA, [2]: colorB, [3]: (kernel: 0 smoothstep / 1 gauss, gauss_factor)
// [4]: (threshold, range); [5]: (output: 0 blended splat / 1 OIT accumulation).
// ARB twin: seed.arbfp.
uniform vec4 program_local[6];
in vec3 v_color;
in float v_value;
in vec2 v_light;
in float v_z;
out vec4 FragColor;
const float PI = 3.14159265358979;

vec3 gradient_scale(float value, float min_value, float max_value) {
    vec3 colorA = program_local[1].rgb;
    vec3 colorB = program_local[2].rgb;
    float n_value = value / (max_value - min_value);
    vec3 pct = vec3(float(n_value));
    pct.r = smoothstep(0.0, 1.0, n_value);
    pct.g = sin(n_value * PI);
    pct.b = pow(n_value, 0.5);
    return mix(colorA, colorB, pct);
}

float gauss(float x, float x0, float sx) {
    float x_x0 = x - x0;
    x_x0 = -1.0 / 2.0 * x_x0 * x_x0 / sx;
    float a = 1.0 / (pow(2.0 * PI * sx, 0.5));
    return a * exp(x_x0);
}

float TransferFunction(float value, float max_value, float min_value) {
    float threshold = program_local[4].x;
    float range = program_local[4].y;
    float n_value = value / (max_value - min_value);
    float maxView = threshold + range;
    float minView = threshold - range;
    bool insideRange = value >= minView && value <= maxView;
    if (insideRange) return smoothstep(0.0, 1.0, n_value);
    return 0.0;
}

void main() {
    float n_dist = 2.0 * length(gl_PointCoord - vec2(0.5));
    if (n_dist > 1.0) discard;
    float min_value = program_local[0].y;
    float max_value = program_local[0].z;
    vec3 color = program_local[0].x > 0.5 ? gradient_scale(v_value, min_value, max_value)
                                          : v_color;
    color = color * v_light.x + v_light.y;
    float alpha;
    if (program_local[3].x > 0.5) {
        alpha = gauss(n_dist, 1.0, program_local[3].y);
    } else {
        alpha = smoothstep(0.0, 1.0, n_dist);
    }
    if (program_local[0].w > 0.5) alpha *= TransferFunction(v_value, max_value, min_value);
    if (isnan(alpha)) alpha = 0.0;
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

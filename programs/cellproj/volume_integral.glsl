// arbvis (new, issue 16): the exact emission-absorption integral of one piece along which
// colour c and attenuation tau are linear (Williams, Max and Stein 1998), for the precise
// volume programs; joined before their main. psi is the mean transmittance over the
// piece, with d0, d1 the optical depth rates (tau x length) at its ends: a scaled erfc
// where tau rises, Dawson's integral where it falls (both as Numerical Recipes fits
// them, relative error near 1e-7), the homogeneous formula where the ends agree to 1e-4.
// CPU mirror: cellproj::transfer::psi_gpu. Then the transfer function on texture2
// (count x 2 RGBA32F: row 0 colour and opacity value, row 1 the scalar positions; the
// including program sets `points` and `inv_unit`) and `integrate`, which composites a
// segment front to back into `acc`, cut at every control point it crosses.
uniform sampler2D texture2;
float erfcx_fit(float y) {
    float t = 1.0 / (1.0 + 0.5 * y);
    float p = -1.26551223 + t * (1.00002368 + t * (0.37409196 + t * (0.09678418 +
              t * (-0.18628806 + t * (0.27886807 + t * (-1.13520398 + t * (1.48851587 +
              t * (-0.82215223 + t * 0.17087277))))))));
    return t * exp(p);
}

float dawson_fit(float x) {
    // Far out, the asymptotic series (relative error below 4e-8 past 20): the fit's
    // x - 2 floor(...) H loses every digit in f32 for a huge x (an opaque cell at a tiny
    // unit distance: 1e29) and gave NaN.
    if (x > 20.0) {
        float r = 1.0 / (x * x);
        return 0.5 / x * (1.0 + r * (0.5 + 0.75 * r));
    }
    if (x < 0.2) {
        float x2 = x * x;
        return x * (1.0 - (2.0 / 3.0) * x2 * (1.0 - 0.4 * x2 * (1.0 - (2.0 / 7.0) * x2)));
    }
    const float H = 0.4;
    float n0 = 2.0 * floor((0.5 / H) * x + 0.5);
    float xp = x - n0 * H;
    float e1 = exp((2.0 * H) * xp);
    float e2 = e1 * e1;
    float d1 = n0 + 1.0;
    float d2 = n0 - 1.0;
    float sum = 0.0;
    for (int k = 0; k < 6; k++) {
        float c = exp(-pow(float(2 * k + 1) * H, 2.0));
        sum += c * (e1 / d1 + 1.0 / (d2 * e1));
        d1 += 2.0;
        d2 -= 2.0;
        e1 *= e2;
    }
    return 0.5641896 * exp(-xp * xp) * sum;
}

float psi(float d0, float d1) {
    d0 = max(d0, 0.0);
    d1 = max(d1, 0.0);
    float diff = abs(d1 - d0);
    if (diff < 1e-4) {
        float d = 0.5 * (d0 + d1);
        if (d < 1e-4) return 1.0 - 0.5 * d + d * d / 6.0;
        return (1.0 - exp(-d)) / d;
    }
    float k = 1.0 / sqrt(2.0 * diff);
    float front = d0 * k;
    float back = d1 * k;
    if (d1 > d0) {
        return 1.7724539 * k * (erfcx_fit(front) - exp(front * front - back * back) * erfcx_fit(back));
    }
    return 2.0 * k * (dawson_fit(front) - exp(back * back - front * front) * dawson_fit(back));
}

// A piece from colour/opacity value f to b (rgba, a = attenuation x unit) of `len`
// object units, `inv_unit` = 1 / unit distance: premultiplied colour and opacity.
vec4 piece(vec4 f, vec4 b, float len, float inv_unit) {
    float d0 = f.a * inv_unit * len;
    float d1 = b.a * inv_unit * len;
    float zeta = exp(-0.5 * (d0 + d1));
    float p = psi(d0, d1);
    return vec4(f.rgb * (1.0 - p) + b.rgb * (p - zeta), 1.0 - zeta);
}

vec4 acc = vec4(0.0);
bool done = false;
int points;
float inv_unit;

float tf_s(int k) {
    return texelFetch(texture2, ivec2(k, 1), 0).r;
}

vec4 tf_c(int k) {
    return texelFetch(texture2, ivec2(k, 0), 0);
}

// Number of control points at or below s (<= when `inclusive`, else < s).
int count_below(float s, bool inclusive) {
    int lo = 0;
    int hi = points;
    while (lo < hi) {
        int mid = (lo + hi) / 2;
        float x = tf_s(mid);
        if (inclusive ? x <= s : x < s) lo = mid + 1; else hi = mid;
    }
    return lo;
}

vec4 tf_at(float s) {
    int k = count_below(s, true);
    if (k == 0) return tf_c(0);
    if (k >= points) return tf_c(points - 1);
    float x0 = tf_s(k - 1);
    float x1 = tf_s(k);
    float w = x1 > x0 ? (s - x0) / (x1 - x0) : 1.0;
    return mix(tf_c(k - 1), tf_c(k), w);
}

void composite(vec4 c) {
    acc += (1.0 - acc.a) * c;
}

// The segment from scalar sf to sb over `len` object units, cut at control points.
void integrate(float sf, float sb, float len) {
    vec4 front = tf_at(sf);
    float u = 0.0;
    if (sb > sf) {
        for (int k = count_below(sf, true); k < points && !done; k++) {
            float x = tf_s(k);
            if (x >= sb) break;
            float v = (x - sf) / (sb - sf);
            vec4 back = tf_c(k);
            composite(piece(front, back, (v - u) * len, inv_unit));
            front = back;
            u = v;
        }
    } else if (sb < sf) {
        for (int k = count_below(sf, false) - 1; k >= 0 && !done; k--) {
            float x = tf_s(k);
            if (x <= sb) break;
            float v = (x - sf) / (sb - sf);
            vec4 back = tf_c(k);
            composite(piece(front, back, (v - u) * len, inv_unit));
            front = back;
            u = v;
        }
    }
    composite(piece(front, tf_at(sb), (1.0 - u) * len, inv_unit));
}


#version 330
// arbvis (new, issue 27): precise `grid`, the mesh resampled onto a regular grid and ray
// cast (not cell projection: the fast choice where the cells are about the grid's size).
// Each pixel's ray (from the inverse ModelViewProj, near plane to far plane) is clipped
// to the grid's box and sampled at fixed steps; each step, its scalar taken as linear
// between its two samples, is read from the pre-integrated table over lengths up to the
// step (the shorter pieces: the last step, and a step cut where the ray leaves or enters
// the mesh). Front to back; it stops once the transmittance is below the scene's
// termination. Output (C, 1 - T), blended ONE, ONE_MINUS_SRC_ALPHA over the cleared
// target. One branch-free body per step: llvmpipe runs both sides of a branch under a
// mask, so an exact integral for the rare short piece would cost every step.
// texture0: the grid, RG32F 3D, (s m, m) per point, m = 1 inside the mesh and 0 outside:
// filtered, s = (s m) / m is the inside points' weighted mean, and the mesh holds the
// point where m >= 1/2. texture1: the pre-integrated table (sf, sb, length), lengths 0
// to the step.
// program_local[0..3]: inverse ModelViewProj rows; [4]: viewport (width, height, corner
// x, corner y); [5]: (the grid's first point, 0); [6]: (points along x, y, z, step
// length); [7]: (table size along sf and sb, along the length, termination
// transmittance); [8]: (1 / spacing along x, y, z, 0).
uniform sampler3D texture0;
uniform sampler3D texture1;
uniform vec4 program_local[9];
out vec4 color;

vec3 grid_lo;
vec3 inv_spacing;
vec3 dims;

// (scalar, inside weight) at object point p.
vec2 sample_at(vec3 p) {
    vec3 tc = ((p - grid_lo) * inv_spacing + 0.5) / dims;
    vec2 v = texture(texture0, tc).rg;
    return vec2(clamp(v.x / max(v.y, 1e-6), 0.0, 1.0), v.y);
}

// The piece from scalar sf to sb over `len` (at most the step) from the table.
vec4 piece_table(float sf, float sb, float len) {
    vec2 size = program_local[7].xy;
    vec3 at = vec3(vec2(sf, sb) * (size.x - 1.0), len / program_local[6].w * (size.y - 1.0));
    return texture(texture1, (at + 0.5) / size.xxy);
}

vec4 acc = vec4(0.0);

void main() {
    mat4 inv = transpose(mat4(program_local[0], program_local[1], program_local[2],
                              program_local[3]));
    vec2 pixel = gl_FragCoord.xy - program_local[4].zw;
    vec2 ndc = 2.0 * pixel / program_local[4].xy - 1.0;
    vec4 n = inv * vec4(ndc, -1.0, 1.0);
    vec4 f = inv * vec4(ndc, 1.0, 1.0);
    vec3 ray_o = n.xyz / n.w;
    vec3 e = f.xyz / f.w - ray_o;
    float ray_end = length(e);
    vec3 ray_d = e / ray_end;
    grid_lo = program_local[5].xyz;
    inv_spacing = program_local[8].xyz;
    dims = program_local[6].xyz;
    float dt = program_local[6].w;
    float termination = program_local[7].z;
    // The ray within the box of the grid's points.
    vec3 grid_hi = grid_lo + (dims - 1.0) / inv_spacing;
    vec3 safe_d = mix(ray_d, vec3(1e-30), equal(ray_d, vec3(0.0)));
    vec3 t0 = (grid_lo - ray_o) / safe_d;
    vec3 t1 = (grid_hi - ray_o) / safe_d;
    vec3 near = min(t0, t1);
    vec3 far = max(t0, t1);
    float t = max(max(near.x, near.y), max(near.z, 0.0));
    float t_out = min(min(far.x, far.y), min(far.z, ray_end));
    if (t >= t_out) discard;
    // At most 65,536 steps: never endless, whatever the uniforms.
    int steps = int(min(ceil((t_out - t) / dt), 65536.0));
    vec2 a = sample_at(ray_o + t * ray_d);
    for (int k = 0; k < steps && 1.0 - acc.a >= termination; k++) {
        float len = min(dt, t_out - t);
        vec2 b = sample_at(ray_o + (t + len) * ray_d);
        // The part inside the mesh: all, none, or up to where the inside weight crosses
        // 1/2 (the boundary), from the end that is inside. A sample with no inside point
        // around it has no scalar (0 / 0): the crossing takes the other end's.
        float in_a = step(0.5, a.y);
        float in_b = step(0.5, b.y);
        float cut = clamp((a.y - 0.5) / (a.y - b.y + 1e-30), 0.0, 1.0);
        float s_cut = mix(mix(b.x, a.x, step(1e-3, a.y)), mix(a.x, b.x, step(1e-3, b.y)), cut);
        float sf = mix(s_cut, a.x, in_a);
        float sb = mix(s_cut, b.x, in_b);
        float part = in_a * in_b + abs(in_a - in_b) * mix(1.0 - cut, cut, in_a);
        vec4 c = piece_table(sf, sb, part * len);
        acc += (1.0 - acc.a) * c * max(in_a, in_b);
        a = b;
        t += len;
    }
    if (acc.a <= 0.0) discard;
    color = acc;
}

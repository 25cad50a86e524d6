#version 330
// arbvis (new): v3o2's 3D opacity in precise mode as a single-pass ray caster (GLSL only:
// ARB fragment programs have no loops). Drawn on the box's far faces, one fragment per
// pixel; tags and channel placeholders as in slice_precise.frag ("!tag": kept when the
// scene lacks the tag).
//  - exact ray-box entry per pixel;
//  - point sampling: the chord is cut into N = ceil(L / step) equal steps sampled at
//    their midpoints (the reference's own rule), or with jitter into steps of the step
//    length after a first one of a per-pixel fraction of it; each sample with the exact
//    opacity of its step a' = 1 - (1 - a)^(h / reference) and slice_precise's
//    classification;
//  - pre-integrated (one attribute, tag preint): samples at both ends of each full step,
//    the step's premultiplied colour and opacity read from the 256 x 256 table on unit 6
//    (front value, back value), and the partial last step by its midpoint;
//  - front to back, stopping once the accumulated alpha reaches local[9].w;
//  - empty-space skipping (tag skip, point sampling only): texture5 holds, per brick, 1
//    where some sample can have alpha > 0 (levels over the brick and one voxel around it
//    against the tables' alpha), so samples in an empty brick are skipped exactly.
//  - neighbours (tag neighbours, one attribute, not paged): texture0 holds each voxel's
//    2x2x2 levels as bytes of an RG32UI texel, so a sample is one fetch (level_at).
//  - paged (tag paged: a survey from a store): texture0 is the brick atlas, texture7 the
//    page table, one RGBA32F entry per level-0 brick of the window (the INDEX of seed
//    002's INDEX-DATA: see src/volume/index_data.rs): w = 2^-level of the resident brick
//    that covers it (0: nothing to draw there), xyz its offset, so that level-0 voxel
//    coordinate v reads the atlas at v * w / atlas + xyz (one MAD, as the clip's offset
//    encoding). Steps are the base steps' lattice; in a level-l page a sample stands for
//    2^l of them (its opacity corrected for that length), at their middle; empty pages
//    are skipped to the first step past them.
// Locals: 1..3 coefficients; 4 = (1/reference or 0, step length, 0 or 1, 0); 5 = lookup;
// 6 = box size; 7 = box half size; 8 = orthographic: the ray direction (unit) /
// perspective: the eye; 9 = (bricks per unit texture coordinate, stop alpha); paged:
// 10 = (window size in level-0 voxels, brick side), 11 = (window's first voxel, 0),
// 12 = (1 / atlas size in texels, 0), 13 = (first page of the table, 0). Every variant:
// 16, 17 = window position to NDC (scale, offset), 18..21 = the rows of the inverse
// view-projection (NDC to the box's coordinates); point sampling: 22, 23 = the box, in
// texture coordinates, of the bricks where some sample can have alpha above 0 (the
// whole volume when not computed): the steps outside it are not taken (margins).
// Output: premultiplied colour and coverage, blended ONE, ONE_MINUS_SRC_ALPHA.
in vec4 v_texcoord0;
uniform sampler3D texture0;  // [!neighbours]
uniform usampler3D texture0;  // [neighbours]
uniform sampler2D texture2;
uniform sampler2D texture3;  // [secondary]
uniform sampler2D texture4;  // [tertiary]
uniform sampler3D texture5;  // [skip]
uniform sampler2D texture6;  // [preint]
uniform sampler1D texture6;  // [baked]
uniform vec4 program_local[24];
uniform sampler3D texture7;  // [paged]
out vec4 frag_color;
// @sampling

// The level at texture coordinate tc: the volume unit's linear read, or (tag neighbours,
// one attribute) the 2x2x2 levels around tc from one texel of neighbour words
// (Prepared::neighbour_words), interpolated here as GL_LINEAR with CLAMP_TO_EDGE reads
// them: texel space u = tc * size - 0.5; below the first texel centre (u < 0) every
// corner is the first texel, so the weights are 0 there.
vec4 level_at(vec3 tc) { return volume_at(texture0, tc); }  // [!neighbours]
vec4 level_at(vec3 tc) {  // [neighbours]
    ivec3 size = textureSize(texture0, 0);  // [neighbours]
    vec3 u = tc * vec3(size) - 0.5;  // [neighbours]
    vec3 b = floor(u);  // [neighbours]
    vec3 f = mix(u - b, vec3(0.0), lessThan(b, vec3(0.0)));  // [neighbours]
    uvec2 w = texelFetch(texture0, clamp(ivec3(b), ivec3(0), size - 1), 0).xy;  // [neighbours]
    vec4 near = vec4(uvec4(w.x, w.x >> 8u, w.x >> 16u, w.x >> 24u) & 255u);  // [neighbours]
    vec4 far = vec4(uvec4(w.y, w.y >> 8u, w.y >> 16u, w.y >> 24u) & 255u);  // [neighbours]
    vec4 c = mix(near, far, f.z) / 255.0;  // [neighbours]
    vec2 e = mix(c.xz, c.yw, f.x);  // [neighbours]
    return vec4(mix(e.x, e.y, f.y));  // [neighbours]
}  // [neighbours]

vec4 classify(vec3 tc) {
    vec4 lookup = program_local[5];
    vec4 coord = level_at(tc) * lookup.x + lookup.y;
    vec4 lut = table_at(texture2, vec2(coord.@1, 0.5));
    vec4 col = program_local[1] * lut;
    lut = table_at(texture3, vec2(coord.@2, 0.5));  // [secondary]
    col = program_local[2] * lut + col;  // [sum secondary]
    col = col * (program_local[2] * lut);  // [product secondary]
    lut = table_at(texture4, vec2(coord.@3, 0.5));  // [tertiary]
    col = program_local[3] * lut + col;  // [sum tertiary]
    col = col * (program_local[3] * lut);  // [product tertiary]
    col = col * lookup.z;  // [sum]
    return clamp(col, 0.0, 1.0);
}

// The steps j0 <= j < j1 of a ray that can lie in the box of locals 22, 23 (samples
// outside it have alpha 0): `count` steps of length h along tc = entry + along t, step j
// sampled at t = t0 + (j + 1/2) h, on a chord of length `chord`.
ivec2 occupied_steps(vec3 entry, vec3 along, float t0, float h, int count, float chord) {
    vec3 lo = program_local[22].xyz;
    vec3 hi = program_local[23].xyz;
    bvec3 parallel = equal(along, vec3(0.0));
    vec3 inv = 1.0 / mix(along, vec3(1.0), parallel);
    vec3 ta = (lo - entry) * inv;
    vec3 tb = (hi - entry) * inv;
    // A ray parallel to an axis's faces lies in that slab everywhere (its entry does, on
    // a face included) or nowhere.
    bvec3 inside = bvec3(step(lo, entry) * step(entry, hi));
    ta = mix(ta, mix(vec3(1e30), vec3(-1e30), inside), parallel);
    tb = mix(tb, vec3(1e30), parallel);
    vec3 near = min(ta, tb);
    vec3 far = max(ta, tb);
    float t_in = max(max(near.x, near.y), near.z);
    float t_out = min(min(far.x, far.y), far.z);
    if (!(t_in <= t_out)) return ivec2(0);
    t_in = clamp(t_in, 0.0, chord);
    t_out = clamp(t_out, 0.0, chord);
    // A step more each way than the box needs: rounding never drops a sample inside it.
    int j0 = max(int(floor((t_in - t0) / h - 0.5)) - 1, 0);
    int j1 = min(int(ceil((t_out - t0) / h - 0.5)) + 2, count);
    return ivec2(j0, max(j0, j1));
}

void main() {
    vec4 correction = program_local[4];
    vec4 lookup = program_local[5];  // [preint]
    vec3 size = program_local[6].xyz;
    vec3 half_size = program_local[7].xyz;
    // The pixel's own ray: its centre unprojected (not the far face's interpolated
    // coordinate, which a rasterizer that snaps vertices to its sub-pixel grid moves by
    // up to 1/512 pixel), and where it leaves the box.
    vec4 ndc = vec4(gl_FragCoord.xyz, 1.0) * program_local[16] + program_local[17];
    vec4 h_ray = vec4(dot(program_local[18], ndc), dot(program_local[19], ndc),
                      dot(program_local[20], ndc), dot(program_local[21], ndc));
    vec3 on_ray = h_ray.xyz / h_ray.w;
    vec3 dir = program_local[8].xyz;  // [orthographic]
    vec3 dir = normalize(on_ray - program_local[8].xyz);  // [perspective]
    vec3 to_far = (half_size - on_ray * sign(dir)) / max(abs(dir), vec3(1e-20));
    vec3 p_exit = on_ray + dir * min(min(to_far.x, to_far.y), to_far.z);
    // Back from the exit to the entry: the nearest face behind, per axis.
    vec3 q = mix(p_exit, -p_exit, lessThan(dir, vec3(0.0)));
    vec3 back3 = (half_size + q) / max(abs(dir), vec3(1e-20));
    float chord = min(min(back3.x, back3.y), back3.z);
    chord = min(chord, length(p_exit - program_local[8].xyz));  // [perspective]
    // A pixel the rasterizer covers whose own ray misses the box (its silhouette, where
    // vertices snap) has nothing to draw.
    if (!(chord > 0.0)) discard;
    float stop = program_local[9].w;
    vec4 acc = vec4(0.0);
    int steps = max(1, int(ceil(chord / correction.y - 1e-4)));  // [!preint !jitter]
    float h = chord / float(steps);  // [!preint !jitter]
    float k = h * correction.x + correction.z;  // [!preint !jitter]
    // Sample j sits at texture coordinate start + delta * j.
    vec3 delta = dir * h / size;  // [!preint !jitter]
    vec3 start = (p_exit - dir * chord + half_size) / size + 0.5 * delta;  // [!preint !jitter]
    vec3 bricks = program_local[9].xyz;  // [skip]
    ivec3 last = textureSize(texture5, 0) - 1;  // [skip]
    vec3 safe = mix(delta, vec3(1e-30), equal(delta, vec3(0.0)));  // [skip]
    vec3 voxels = program_local[10].xyz;  // [paged]
    float side = program_local[10].w;  // [paged]
    vec3 first_voxel = program_local[11].xyz;  // [paged]
    vec3 per_texel = program_local[12].xyz;  // [paged]
    ivec3 first_page = ivec3(program_local[13].xyz);  // [paged]
    ivec3 last_page = textureSize(texture7, 0) - 1;  // [paged]
    vec3 safe = mix(delta, vec3(1e-30), equal(delta, vec3(0.0)));  // [paged]
    int j = 0;  // [paged]
    while (j < steps && acc.a < stop) {  // [paged]
        vec3 v = (start + delta * float(j)) * voxels + first_voxel;  // [paged]
        ivec3 page = clamp(ivec3(floor(v / side)) - first_page, ivec3(0), last_page);  // [paged]
        vec4 entry = texelFetch(texture7, page, 0);  // [paged]
        if (entry.w == 0.0) {  // [paged]
            // Nothing here: on to the first step whose middle is past this page.
            vec3 lo = (vec3(page + first_page) * side - first_voxel) / voxels;  // [paged]
            vec3 hi = (vec3(page + first_page + 1) * side - first_voxel) / voxels;  // [paged]
            vec3 bound = (mix(lo, hi, greaterThan(delta, vec3(0.0))) - start) / safe;  // [paged]
            bound = mix(bound, vec3(1e30), equal(delta, vec3(0.0)));  // [paged]
            j = int(clamp(ceil(min(min(bound.x, bound.y), bound.z) - 1e-3), float(j + 1), float(steps)));  // [paged]
            continue;  // [paged]
        }  // [paged]
        int m = min(int(1.0 / entry.w + 0.5), steps - j);  // [paged]
        vec3 at = start + delta * (float(j) + 0.5 * float(m - 1));  // [paged]
        v = at * voxels + first_voxel;  // [paged]
        page = clamp(ivec3(floor(v / side)) - first_page, ivec3(0), last_page);  // [paged]
        entry = texelFetch(texture7, page, 0);  // [paged]
        j += m;  // [paged]
        if (entry.w == 0.0) continue;  // [paged]
        vec4 col = classify(v * (entry.w * per_texel) + entry.xyz);  // [paged]
        float a = 1.0 - pow(1.0 - col.a, k * float(m));  // [paged]
        acc += (1.0 - acc.a) * vec4(col.rgb * a, a);  // [paged]
    }  // [paged]
    ivec2 range = occupied_steps(start - 0.5 * delta, dir / size, 0.0, h, steps, chord);  // [!preint !jitter !paged]
    int j = range.x;  // [!preint !jitter !paged]
    while (j < range.y && acc.a < stop) {  // [!preint !jitter !paged]
        int end = range.y;  // [!preint !jitter !paged]
        vec3 cell = floor((start + delta * float(j)) * bricks);  // [skip]
        // First sample past this brick along each axis (a little early is harmless).
        vec3 lo = cell / bricks;  // [skip]
        vec3 hi = (cell + 1.0) / bricks;  // [skip]
        vec3 bound = (mix(lo, hi, greaterThan(delta, vec3(0.0))) - start) / safe;  // [skip]
        bound = mix(bound, vec3(1e30), equal(delta, vec3(0.0)));  // [skip]
        float first = ceil(min(min(bound.x, bound.y), bound.z) - 1e-3);  // [skip]
        end = int(clamp(first, float(j + 1), float(range.y)));  // [skip]
        bool empty = texelFetch(texture5, clamp(ivec3(cell), ivec3(0), last), 0).r == 0.0;  // [skip]
        if (empty) { j = end; continue; }  // [skip]
        for (; j < end && acc.a < stop; j++) {  // [!preint !jitter !paged]
            vec4 col = classify(start + delta * float(j));  // [!preint !jitter !paged]
            float a = 1.0 - pow(1.0 - col.a, k);  // [!preint !jitter !paged]
            acc += (1.0 - acc.a) * vec4(col.rgb * a, a);  // [!preint !jitter !paged]
        }  // [!preint !jitter !paged]
    }  // [!preint !jitter !paged]
    // Jitter: steps of the step length h, the first one ending at u h with u in (0, 1]
    // per pixel, so that steps whose length divides the voxel spacing do not sample every
    // ray at the same place in its cells; the first and last steps by their midpoints with
    // their own opacity. Baked (one attribute): full steps read colour and opacity for h
    // from a 4081-entry table (16 per level) on unit 6, premultiplied, without pow.
    float h = correction.y;  // [jitter]
    float u = 1.0 - fract(52.9829189 * fract(dot(gl_FragCoord.xy, vec2(0.06711056, 0.00583715))));  // [jitter]
    vec3 entry = (p_exit - dir * chord + half_size) / size;  // [jitter]
    vec3 along = dir / size;  // [jitter]
    float first = min(u * h, chord);  // [jitter]
    vec4 col = classify(entry + along * (0.5 * first));  // [jitter]
    float a = 1.0 - pow(1.0 - col.a, first * correction.x + correction.z);  // [jitter]
    acc = vec4(col.rgb * a, a);  // [jitter]
    int full = int(max(floor((chord - first) / h + 1e-4), 0.0));  // [jitter]
    vec3 start = entry + along * (first + 0.5 * h);  // [jitter]
    vec3 delta = along * h;  // [jitter]
    ivec2 range = occupied_steps(entry, along, first, h, full, chord);  // [jitter]
    float k = h * correction.x + correction.z;  // [jitter !baked]
    for (int j = range.x; j < range.y && acc.a < stop; j++) {  // [jitter !baked]
        vec4 col = classify(start + delta * float(j));  // [jitter !baked]
        float a = 1.0 - pow(1.0 - col.a, k);  // [jitter !baked]
        acc += (1.0 - acc.a) * vec4(col.rgb * a, a);  // [jitter !baked]
    }  // [jitter !baked]
    // Two steps a turn: half the termination tests.
    int j = range.x;  // [baked]
    for (; j + 1 < range.y && acc.a < stop; j += 2) {  // [baked]
        vec3 tc = start + delta * float(j);  // [baked]
        float v0 = level_at(tc).r * (4080.0 / 4081.0) + 0.5 / 4081.0;  // [baked]
        float v1 = level_at(tc + delta).r * (4080.0 / 4081.0) + 0.5 / 4081.0;  // [baked]
        acc += (1.0 - acc.a) * step_at(texture6, v0);  // [baked]
        acc += (1.0 - acc.a) * step_at(texture6, v1);  // [baked]
    }  // [baked]
    if (j < range.y && acc.a < stop) {  // [baked]
        float v = level_at(start + delta * float(j)).r * (4080.0 / 4081.0) + 0.5 / 4081.0;  // [baked]
        acc += (1.0 - acc.a) * step_at(texture6, v);  // [baked]
    }  // [baked]
    float done = min(first + float(full) * h, chord);  // [jitter]
    float rest = chord - done;  // [jitter]
    if (rest > 1e-4 * h && acc.a < stop) {  // [jitter]
        vec4 col = classify(entry + along * (done + 0.5 * rest));  // [jitter]
        float a = 1.0 - pow(1.0 - col.a, rest * correction.x + correction.z);  // [jitter]
        acc += (1.0 - acc.a) * vec4(col.rgb * a, a);  // [jitter]
    }  // [jitter]
    // Pre-integrated: full steps of exactly the step length from the entry, then the rest.
    float h = correction.y;  // [preint]
    float full = floor(chord / h + 1e-4);  // [preint]
    float rest = max(chord - full * h, 0.0);  // [preint]
    vec3 delta = dir * h / size;  // [preint]
    vec3 start = (p_exit - dir * chord + half_size) / size;  // [preint]
    float front = level_at(start).r * lookup.x + lookup.y;  // [preint]
    int steps = int(full);  // [preint]
    for (int j = 1; j <= steps && acc.a < stop; j++) {  // [preint]
        float back = level_at(start + delta * float(j)).r * lookup.x + lookup.y;  // [preint]
        acc += (1.0 - acc.a) * step_at(texture6, vec2(front, back));  // [preint]
        front = back;  // [preint]
    }  // [preint]
    if (rest > 1e-4 * h && acc.a < stop) {  // [preint]
        vec4 col = classify(start + delta * (full + 0.5 * rest / h));  // [preint]
        float a = 1.0 - pow(1.0 - col.a, rest * correction.x + correction.z);  // [preint]
        acc += (1.0 - acc.a) * vec4(col.rgb * a, a);  // [preint]
    }  // [preint]
    frag_color = acc;
}

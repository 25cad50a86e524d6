#version 330
// arbvis (new, issue 16): the precise volume, a GPU ray caster walking face neighbours
// (Weiler, Kraus, Merz and Ertl 2003) drawn over a full-screen quad. Each pixel's ray
// (from the inverse ModelViewProj, near plane to far plane) starts in the tetrahedron of
// each entry layer in turn (volume_peel.frag; first, when the eye is inside the mesh,
// in the eye's tetrahedron at the near plane), leaves each tetrahedron through the
// nearest face plane ahead (outward normal N with D.N > 0), integrates the segment
// exactly (cut at every control point of the transfer function crossed, each piece by
// volume_integral.glsl's closed form), and steps to the neighbour across that face,
// until the boundary. Front to back; it stops once the transmittance is below the
// scene's termination, or at the first isovalue crossed (scenes drawing both: the
// isosurface is opaque). Output (C, 1 - T), blended ONE, ONE_MINUS_SRC_ALPHA over the
// cleared target.
// texture0: per tetrahedron 5 RGBA32F texels (4 face planes (N, N.p), then the scalar
// (G, s0): s(p) = G.p + s0), 4096 per row; texture1: RGBA32UI neighbours across the
// four faces (0xFFFFFFFF: boundary); texture2: transfer function, count x 2 RGBA32F
// (row 0 colour and opacity value, row 1 the scalar positions); texture3: isovalues,
// count x 2 (row 0 colours, row 1 values); texture4..11: entry layers (tet, t);
// texture13: RG32UI per tetrahedron (first, count) into texture14, R32UI: the boundary
// tetrahedra a ray leaving it through the boundary may re-enter at once (see reenter);
// texture12: what earlier batches of entry layers accumulated (C, 1 - T), and texture15
// (.r) how far along the ray their walks reached, where program_local[6].w is 1 (a ray
// entering more than 8 times is walked 8 entries a pass; the walk then goes on from
// there and writes the sum so far, unblended, and in output 1 how far it reached, so an
// entry a re-entry of an earlier pass walked already is not walked again).
// program_local[0..3]: inverse ModelViewProj rows; [4]: viewport (width, height,
// corner x, corner y); [5]: (control points, isovalues, termination transmittance,
// eye tetrahedron or -1); [6]: (entry layers, 1 / unit distance, most steps, 1 when
// texture12 holds the earlier batches' sum); [7].x: 1 to look for re-entries.
uniform sampler2D texture0;
uniform usampler2D texture1;
uniform sampler2D texture3;
uniform sampler2D texture4;
uniform sampler2D texture5;
uniform sampler2D texture6;
uniform sampler2D texture7;
uniform sampler2D texture8;
uniform sampler2D texture9;
uniform sampler2D texture10;
uniform sampler2D texture11;
uniform sampler2D texture12;
uniform usampler2D texture13;
uniform usampler2D texture14;
uniform sampler2D texture15;
uniform vec4 program_local[8];
layout(location = 0) out vec4 color;
layout(location = 1) out vec4 reach;

const int ROW = 4096;
const float SLACK = 1.0 / 65536.0;

ivec2 at(int k) {
    return ivec2(k % ROW, k / ROW);
}

vec3 ray_o;
vec3 ray_d;
float ray_end;
// The farthest point along the ray a walk has reached: an entry layer before it was
// walked already (a re-entry the walk found itself).
float reached = -1e30;

// The ray's interval [t_in, t_out] in tetrahedron `tet` (t_in > t_out: it misses).
vec2 interval(int tet) {
    float t_in = -1e30;
    float t_out = 1e30;
    for (int k = 0; k < 4; k++) {
        vec4 plane = texelFetch(texture0, at(tet * 5 + k), 0);
        float dn = dot(plane.xyz, ray_d);
        float num = plane.w - dot(plane.xyz, ray_o);
        if (dn > 1e-7) t_out = min(t_out, num / dn);
        else if (dn < -1e-7) t_in = max(t_in, num / dn);
        else if (num < 0.0) return vec2(1.0, 0.0);
    }
    return vec2(t_in, t_out);
}

// A ray leaving `tet` through the boundary at `t`: the candidate it enters next within
// a ten-thousandth of its length (the nearest entry, a segment longer than a millionth),
// or -1. Where the ray grazes the boundary past an edge, the entry layers can miss that
// re-entry (rasterization gives its face no sample there) and the rest of the ray
// would be lost.
int reenter(int tet, float t, out float t_in) {
    uvec2 range = texelFetch(texture13, at(tet), 0).xy;
    int best = -1;
    float best_t = t + 1e-4 * ray_end;
    for (uint i = 0u; i < range.y; i++) {
        int c = int(texelFetch(texture14, at(int(range.x + i)), 0).r);
        vec2 iv = interval(c);
        if (iv.x >= t - 1e-6 * ray_end && iv.x <= best_t && iv.y - iv.x > 1e-6 * ray_end) {
            best = c;
            best_t = iv.x;
        }
    }
    t_in = max(best_t, t);
    return best;
}

// The segment [a, b] of the ray in a tetrahedron whose scalar is G.p + s0.
void segment(vec4 scalar, float a, float b) {
    float sf = dot(scalar.xyz, ray_o + ray_d * a) + scalar.w;
    float sb = dot(scalar.xyz, ray_o + ray_d * b) + scalar.w;
    float cut = 2.0;
    int hit = -1;
    int isos = int(program_local[5].y + 0.5);
    for (int k = 0; k < isos; k++) {
        float v = texelFetch(texture3, ivec2(k, 1), 0).r;
        bool crossed = (sb > sf && v > sf && v <= sb + SLACK) ||
                       (sb < sf && v >= sb - SLACK && v < sf);
        if (crossed) {
            float f = clamp((v - sf) / (sb - sf), 0.0, 1.0);
            if (f < cut) { cut = f; hit = k; }
        }
    }
    if (hit >= 0) {
        integrate(sf, sf + (sb - sf) * cut, (b - a) * cut);
        vec4 c = texelFetch(texture3, ivec2(hit, 0), 0);
        composite(vec4(c.rgb, 1.0));
        done = true;
    } else {
        integrate(sf, sb, b - a);
    }
    if (1.0 - acc.a < program_local[5].z) done = true;
}

void walk(int tet, float t) {
    int steps = int(program_local[6].z);
    for (int i = 0; i < steps && tet >= 0 && !done; i++) {
        int base = tet * 5;
        float t_exit = 1e30;
        int face = -1;
        for (int k = 0; k < 4; k++) {
            vec4 plane = texelFetch(texture0, at(base + k), 0);
            float dn = dot(plane.xyz, ray_d);
            if (dn > 1e-7) {
                float tk = (plane.w - dot(plane.xyz, ray_o)) / dn;
                if (tk < t_exit) { t_exit = tk; face = k; }
            }
        }
        if (face < 0) break;
        t_exit = max(t_exit, t);
        float a = max(t, 0.0);
        float b = min(t_exit, ray_end);
        if (b > a) segment(texelFetch(texture0, at(base + 4), 0), a, b);
        reached = max(reached, t_exit);
        if (t_exit >= ray_end) break;
        uint next = texelFetch(texture1, at(tet), 0)[face];
        t = t_exit;
        if (next == 0xFFFFFFFFu && program_local[7].x > 0.5) {
            float t_in;
            tet = reenter(tet, t_exit, t_in);
            t = t_in;
        } else {
            tet = next == 0xFFFFFFFFu ? -1 : int(next);
        }
    }
}

vec2 layer(int k, ivec2 p) {
    if (k == 0) return texelFetch(texture4, p, 0).xy;
    if (k == 1) return texelFetch(texture5, p, 0).xy;
    if (k == 2) return texelFetch(texture6, p, 0).xy;
    if (k == 3) return texelFetch(texture7, p, 0).xy;
    if (k == 4) return texelFetch(texture8, p, 0).xy;
    if (k == 5) return texelFetch(texture9, p, 0).xy;
    if (k == 6) return texelFetch(texture10, p, 0).xy;
    return texelFetch(texture11, p, 0).xy;
}

void main() {
    mat4 inv = transpose(mat4(program_local[0], program_local[1], program_local[2],
                              program_local[3]));
    vec2 pixel = gl_FragCoord.xy - program_local[4].zw;
    vec2 ndc = 2.0 * pixel / program_local[4].xy - 1.0;
    vec4 n = inv * vec4(ndc, -1.0, 1.0);
    vec4 f = inv * vec4(ndc, 1.0, 1.0);
    ray_o = n.xyz / n.w;
    vec3 e = f.xyz / f.w - ray_o;
    ray_end = length(e);
    ray_d = e / ray_end;
    points = int(program_local[5].x + 0.5);
    inv_unit = program_local[6].y;
    if (program_local[6].w > 0.5) {
        acc = texelFetch(texture12, ivec2(pixel), 0);
        reached = max(reached, texelFetch(texture15, ivec2(pixel), 0).r);
        // Ended already: opaque (an isosurface) or below the termination.
        done = acc.a >= 1.0 || 1.0 - acc.a < program_local[5].z;
    }
    int eye = int(program_local[5].w);
    if (eye >= 0 && !done) walk(eye, -1.0);
    int layers = int(program_local[6].x + 0.5);
    for (int k = 0; k < layers && !done; k++) {
        vec2 entry = layer(k, ivec2(pixel));
        if (entry.x < 0.0) break;
        // Walked already from an earlier entry that re-entered by itself.
        if (entry.y < reached - 1e-5 * ray_end) continue;
        walk(int(entry.x + 0.5), entry.y);
    }
    // Nothing accumulated: walking its path again adds nothing, so how far it reached
    // need not be kept.
    if (acc.a <= 0.0) discard;
    color = acc;
    reach = vec4(reached, 0.0, 0.0, 1.0);
}

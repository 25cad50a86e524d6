#version 330
// arbvis (new): precise cell projection. What changes from the seed's program:
// - the ray direction is normalized (eye to fragment in perspective, the view
//   direction in orthographic views);
// - the exit is the nearest of the planes the ray leaves through (outward normal N with
//   D.N > 0; the normals are outward), not the nearest positive t: a fragment on an
//   edge has another plane through it, whose t rounds to +-0, and the seed's test
//   `t > 0` then takes the entry for the exit and loses the crossing; planes met at
//   grazing angles (D.N below 1e-7) and degenerate faces (N = 0) are skipped, and t is
//   0 (sb = sf) when no plane is ahead;
// - no table: the first isovalue crossed is found exactly, t_iso = t (v - sf)/(sb - sf)
//   for each isovalue v in (sf, sb] (rising) or [sb, sf) (falling), the exit end widened
//   by 2^-16 so that an isovalue on a shared face, which f32 rounding may leave just
//   beyond this tetrahedron's exit and which the next one excludes at its entry, is drawn;
// - depth is written at the crossing (unless ENTRY_DEPTH is defined: then the entry
//   face's depth stays, which orders the tetrahedra along a ray just as well and lets
//   the depth test run before this program), and the colour may be shaded with the
//   gradient.
// - with PIXEL_RAYS defined (a rasterizer that interpolates from vertices snapped to its
//   sub-pixel grid moves an interpolated position by up to 1/512 pixel, which a face seen
//   nearly edge-on turns into depth), the entry is where the pixel's own ray (its centre
//   unprojected) meets the face's plane (the interpolated position's, from its
//   derivatives), and sf the scalar there.
// program_local[0..3]: ModelViewProj rows; [4]: eye in object space (xyz), w = 1 for
// perspective, 0 for orthographic; [5]: view direction (orthographic, unit);
// [6]: x = isovalue count, y = shading on (1) / off (0), z = ambient term;
// [7..10]: inverse ModelViewProj rows; [11]: window position to NDC (scale xy, offset zw).
// texture0: count x 2 RGBA32F, row 0 the colours, row 1 the values (ascending).
uniform vec4 program_local[12];
uniform sampler2D texture0;
in float v_sf;
in vec3 v_pos, v_vertex3, v_gradient;
flat in vec3 v_normal0, v_normal1, v_normal2;
out vec4 color;
const float SLACK = 1.0 / 65536.0;

float exit_along(vec3 D, vec3 aux1, vec3 n, float t) {
    float dn = dot(D, n);
    if (dn < 1e-7) return t; // entering through it, grazing it, or degenerate
    return min(t, max(dot(aux1, n) / dn, 0.0));
}

void main() {
#ifdef PIXEL_RAYS
    mat4 inv = transpose(mat4(program_local[7], program_local[8], program_local[9],
                              program_local[10]));
    vec2 ndc = gl_FragCoord.xy * program_local[11].xy + program_local[11].zw;
    vec4 near = inv * vec4(ndc, -1.0, 1.0);
    vec4 far = inv * vec4(ndc, 1.0, 1.0);
    vec3 o = near.xyz / near.w;
    vec3 d = normalize(far.xyz / far.w - o);
    vec3 face = cross(dFdx(v_pos), dFdy(v_pos));
    float dn = dot(d, face);
    vec3 entry = abs(dn) > 1e-6 * length(face) ? o + d * (dot(v_pos - o, face) / dn) : v_pos;
#else
    vec3 entry = v_pos;
#endif
    vec3 D = program_local[4].w > 0.5 ? normalize(entry - program_local[4].xyz)
                                      : program_local[5].xyz;
    vec3 aux1 = v_vertex3 - entry;
    float big = 1e30;
    float t = exit_along(D, aux1, v_normal0, big);
    t = exit_along(D, aux1, v_normal1, t);
    t = exit_along(D, aux1, v_normal2, t);
    if (t == big) t = 0.0;
    float sf = v_sf + dot(v_gradient, entry - v_pos);
    float sb = sf + t * dot(v_gradient, D);
    int count = int(program_local[6].x + 0.5);
    int hit = -1;
    float best = 2.0;
    for (int k = 0; k < count; k++) {
        float v = texelFetch(texture0, ivec2(k, 1), 0).r;
        bool crossed = (sb > sf && v > sf && v <= sb + SLACK) ||
                       (sb < sf && v >= sb - SLACK && v < sf);
        if (crossed) {
            float f = (v - sf) / (sb - sf);
            if (f < best) { best = f; hit = k; }
        }
    }
    if (hit < 0) discard;
    vec4 c = texelFetch(texture0, ivec2(hit, 0), 0);
#ifndef ENTRY_DEPTH
    vec3 p = entry + D * (t * best);
    vec4 clip = vec4(dot(program_local[0], vec4(p, 1.0)), dot(program_local[1], vec4(p, 1.0)),
                     dot(program_local[2], vec4(p, 1.0)), dot(program_local[3], vec4(p, 1.0)));
    gl_FragDepth = clamp(0.5 * clip.z / clip.w + 0.5, 0.0, 1.0);
#endif
    if (program_local[6].y > 0.5) {
        vec3 g = v_gradient;
        float len = length(g);
        vec3 n = len > 0.0 ? g / len : -D;
        if (dot(n, D) > 0.0) n = -n; // toward the viewer
        float diffuse = max(dot(n, -D), 0.0);
        float ambient = program_local[6].z;
        c.rgb *= ambient + (1.0 - ambient) * diffuse;
    }
    color = c;
}

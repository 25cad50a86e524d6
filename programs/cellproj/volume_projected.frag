#version 330
// arbvis (new, issue 16): the precise volume as a projection (the issue's third option):
// the faithful draw (front faces, back to front by the CPU's MPVONC order, blended ONE,
// ONE_MINUS_SRC_ALPHA) into a float target, with precise.frag's exit (normalized
// direction, the nearest plane the ray leaves through, grazing planes skipped) and the
// exact segment integral of volume_integral.glsl instead of the 8-bit table. Exact
// wherever the order is (convex meshes without cycles); a camera inside the mesh or a
// misordered non-convex mesh is not.
// program_local[4]: eye in object space, w = 1 for perspective; [5]: view direction
// (orthographic, unit); [6]: (control points, 1 / unit distance, 0, 0).
uniform vec4 program_local[7];
in float v_sf;
in vec3 v_pos, v_vertex3, v_gradient;
flat in vec3 v_normal0, v_normal1, v_normal2;
out vec4 color;

float exit_along(vec3 D, vec3 aux1, vec3 n, float t) {
    float dn = dot(D, n);
    if (dn < 1e-7) return t;
    return min(t, max(dot(aux1, n) / dn, 0.0));
}

void main() {
    vec3 D = program_local[4].w > 0.5 ? normalize(v_pos - program_local[4].xyz)
                                      : program_local[5].xyz;
    vec3 aux1 = v_vertex3 - v_pos;
    float big = 1e30;
    float t = exit_along(D, aux1, v_normal0, big);
    t = exit_along(D, aux1, v_normal1, t);
    t = exit_along(D, aux1, v_normal2, t);
    if (t == big) t = 0.0;
    points = int(program_local[6].x + 0.5);
    inv_unit = program_local[6].y;
    integrate(v_sf, v_sf + t * dot(v_gradient, D), t);
    if (acc.a <= 0.0) discard;
    color = acc;
}

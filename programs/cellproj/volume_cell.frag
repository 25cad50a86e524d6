#version 330
// arbvis, precise `table` with the exit per fragment: the ray through this fragment's
// point x (on whichever face of the cell is drawn: a front face, or the back face that
// covers three front faces' pixels at once) meets each face plane (n, d) at
// x + u dir, u = (d - n.x) / n.dir. Planes it enters through (n.dir < 0) bound the
// segment from below, planes it leaves through from above: the segment is
// [max entering u, min leaving u], its scalars s(x) + u G.dir at both ends and its
// length (u_out - u_in) |dir|, read from the pre-integrated table as volume.frag does.
// A ray that meets no leaving plane, or whose bounds cross (a grazing ray, rounding),
// gets no segment. program_local[0..1]: (sf, sb, length) to texture coordinates;
// program_local[2]: the eye in object space (w = 1), or for a parallel view the
// direction into the scene (w = 0).
uniform sampler3D texture0;
uniform vec4 program_local[3];
in vec3 v_position;
in float v_scalar;
flat in vec4 v_plane0, v_plane1, v_plane2, v_plane3;
flat in vec3 v_gradient;
out vec4 color;
void bound(vec4 plane, vec3 dir, inout float u_in, inout float u_out) {
    float along = dot(plane.xyz, dir);
    float u = (plane.w - dot(plane.xyz, v_position)) / along;
    if (along < 0.0) u_in = max(u_in, u);
    if (along > 0.0) u_out = min(u_out, u);
}
void main() {
    vec4 eye = program_local[2];
    vec3 dir = eye.w > 0.0 ? v_position - eye.xyz : eye.xyz;
    float u_in = -1e30, u_out = 1e30;
    bound(v_plane0, dir, u_in, u_out);
    bound(v_plane1, dir, u_in, u_out);
    bound(v_plane2, dir, u_in, u_out);
    bound(v_plane3, dir, u_in, u_out);
    if (!(u_out > u_in) || u_out >= 1e29 || u_in <= -1e29) {
        u_in = 0.0;
        u_out = 0.0;
    }
    float rate = dot(v_gradient, dir);
    vec3 coord = vec3(v_scalar + u_in * rate, v_scalar + u_out * rate,
                      (u_out - u_in) * length(dir));
    color = texture(texture0, coord * program_local[0].xyz + program_local[1].xyz);
}

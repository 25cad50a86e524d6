#version 330
// arbvis: GLSL twin of cellproj/volume_orthographic.arbfp (the t_i from the vertices,
// D normalized, then the pre-integrated 3D table at (sf, sb, length)).
uniform sampler3D texture0;
uniform vec4 program_local[2];
in float v_sf;
in vec3 v_ti;
in float v_gd;
out vec4 color;
void main() {
    float t = 10000.0;
#ifdef GUARDED_EXIT
    // Precise `table` (orthographic.vert with GUARDED_EXIT): planes the ray enters through
    // arrive as 1e30, so the nearest of the others is the exit, clamped to >= 0; none
    // (a flat cell) is no segment. See volume.frag.
    t = max(min(min(v_ti.x, v_ti.y), v_ti.z), 0.0);
    if (t >= 1e29) t = 0.0;
#else
    if (v_ti.x > 0.0) t = min(t, v_ti.x);
    if (v_ti.y > 0.0) t = min(t, v_ti.y);
    if (v_ti.z > 0.0) t = min(t, v_ti.z);
#endif
    vec3 coord = vec3(v_sf, v_sf + t * v_gd, t);
    color = texture(texture0, coord * program_local[0].xyz + program_local[1].xyz);
}

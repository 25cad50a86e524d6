#version 330
// arbvis: GLSL twin of cellproj/volume.arbfp (the seed's exit computation, then the
// pre-integrated 3D table at (sf, sb, length)).
uniform sampler3D texture0;
uniform vec4 program_local[2];
in float v_sf;
in vec3 v_normal0, v_normal1, v_normal2, v_gradient, v_dir, v_vOS, v_vertex3;
out vec4 color;
void main() {
    float t = 10000.0;
    vec3 aux1 = v_vertex3 - v_vOS;
    float ti;
    ti = dot(aux1, v_normal0) * (1.0 / dot(v_dir, v_normal0));
    if (ti > 0.0) t = min(t, ti);
    ti = dot(aux1, v_normal1) * (1.0 / dot(v_dir, v_normal1));
    if (ti > 0.0) t = min(t, ti);
    ti = dot(aux1, v_normal2) * (1.0 / dot(v_dir, v_normal2));
    if (ti > 0.0) t = min(t, ti);
    vec3 coord = vec3(v_sf, v_sf + t * dot(v_gradient, v_dir), t * length(v_dir));
    color = texture(texture0, coord * program_local[0].xyz + program_local[1].xyz);
}

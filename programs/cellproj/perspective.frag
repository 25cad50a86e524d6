#version 330
// arbvis: GLSL twin of cellproj/perspective.arbfp (the seed's Cg fragment program,
// line for line, plus the discard where the table is empty).
uniform sampler2D texture0; // the isosurface table: s = sf, t = sb
in float v_sf;
in vec3 v_normal0, v_normal1, v_normal2, v_gradient, v_dir, v_vOS, v_vertex3;
out vec4 color;
void main() {
    float t = 10000.0;
    float ti;
    vec3 aux1;
    float aux2;
    vec3 dir_n = v_dir;
    aux1 = v_vertex3 - v_vOS;
    aux2 = 1.0 / dot(dir_n, v_normal0);
    ti = dot(aux1, v_normal0) * aux2;
    if (ti > 0.0) t = min(t, ti);
    aux2 = 1.0 / dot(v_dir, v_normal1);
    ti = dot(aux1, v_normal1) * aux2;
    if (ti > 0.0) t = min(t, ti);
    aux2 = 1.0 / dot(dir_n, v_normal2);
    ti = dot(aux1, v_normal2) * aux2;
    if (ti > 0.0) t = min(t, ti);
    aux1.x = v_sf + t * dot(v_gradient, dir_n);
    aux1.y = v_sf;
    color = texture(texture0, aux1.yx);
    if (color.a < 0.5) discard;
}

#version 330
// arbvis: GLSL twin of cellproj/orthographic.arbfp.
uniform sampler2D texture0;
in float v_sf;
in vec3 v_ti;
in float v_gd;
out vec4 color;
void main() {
    float t = 10000.0;
    if (v_ti.x > 0.0) t = min(t, v_ti.x);
    if (v_ti.y > 0.0) t = min(t, v_ti.y);
    if (v_ti.z > 0.0) t = min(t, v_ti.z);
    vec2 aux1 = vec2(v_sf + t * v_gd, v_sf);
    color = texture(texture0, aux1.yx);
    if (color.a < 0.5) discard;
}

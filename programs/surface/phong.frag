#version 330
// arbvis (new): GLSL twin of surface/phong.arbfp.
in vec4 v_normal;
in vec4 v_colour;
uniform vec4 program_local[2];
out vec4 frag_color;
void main() {
    vec4 k = program_local[1];
    float d = abs(dot(normalize(v_normal.xyz), program_local[0].xyz)) * k.y + k.x;
    frag_color = vec4(v_colour.xyz * d * k.z, k.z);
}

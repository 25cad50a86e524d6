#version 330
// arbvis (new): GLSL twin of quad/quad.arbfp.
in vec4 v_texcoord0;
uniform vec4 program_local[2];
out vec4 frag_color;
void main() {
    vec4 c = mix(program_local[0], program_local[1], v_texcoord0.x);
    frag_color = vec4(c.xyz * v_texcoord0.y, c.w);
}

#version 330
// arbvis (new): GLSL twin of section/faithful.arbfp.
in vec4 v_texcoord0;
uniform sampler2D texture0;
uniform sampler1D texture1;
uniform vec4 program_local[1];
out vec4 frag_color;
void main() {
    vec4 level = texture(texture0, v_texcoord0.xy);
    if (level.w - 0.999 < 0.0) discard;
    vec4 colour = texture(texture1, level.x * 0.99609375 + 0.001953125);
    float k = program_local[0].x;
    frag_color = vec4(colour.xyz * k, k);
}

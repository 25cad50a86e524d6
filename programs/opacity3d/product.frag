#version 330
// arbvis (port): GLSL twin of opacity3d/product.arbfp, instruction for instruction.
in vec4 v_texcoord0;
uniform sampler3D texture0;
uniform sampler2D texture2;
uniform sampler2D texture3;
uniform sampler2D texture4;
uniform vec4 program_local[4];
out vec4 frag_color;
void main() {
    vec4 rgba_frag = texture(texture0, v_texcoord0.xyz);
    vec4 lut1 = texture(texture2, vec2(rgba_frag.g));
    vec4 lut2 = texture(texture3, vec2(rgba_frag.b));
    vec4 lut3 = texture(texture4, vec2(rgba_frag.r));
    vec4 temp1 = program_local[1] * lut1;
    vec4 temp2 = program_local[2] * lut2;
    vec4 temp3 = program_local[3] * lut3;
    vec4 temp4 = temp2 * temp1;
    frag_color = temp4 * temp3;
}

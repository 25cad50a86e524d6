#version 330
// arbvis (new): GLSL twin of opacity3d/product_precise.arbfp: v3o2's product combination (eqs. 2-3) in precise
// mode (texel-centre table lookup, clamped result, opacity correction a' = 1 - (1 - a)^k).
in vec4 v_texcoord0;
uniform sampler3D texture0;
uniform sampler2D texture2;
uniform sampler2D texture3;
uniform sampler2D texture4;
uniform vec4 program_local[6];
out vec4 frag_color;
void main() {
    vec4 lookup = program_local[5];
    vec4 rgba_frag = texture(texture0, v_texcoord0.xyz);
    vec4 coord = rgba_frag * lookup.x + lookup.y;
    vec4 lut1 = texture(texture2, vec2(coord.g));
    vec4 lut2 = texture(texture3, vec2(coord.b));
    vec4 lut3 = texture(texture4, vec2(coord.r));
    vec4 temp = clamp((program_local[2] * lut2) * (program_local[1] * lut1) * (program_local[3] * lut3), 0.0, 1.0);
    float transmit = pow(1.0 - temp.w, program_local[4].x);
    frag_color = vec4(temp.xyz, 1.0 - transmit);
}

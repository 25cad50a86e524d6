#version 330
// arbvis (new): where a slicing frame's time goes (`arbvis bench --breakdown`): the same
// slices drawn with less work per fragment, a template with the tags of
// slice_precise.frag: nothing (a constant colour), fetch2d (one fetch of a small 2D
// texture: the fill-rate baseline), fetch3d (one fetch of the packed volume), table1 and
// table3 (one or three dependent table fetches after it).
in vec4 v_texcoord0;
uniform sampler3D texture0;  // [fetch3d]
uniform sampler2D texture2;
uniform sampler2D texture3;  // [table3]
uniform sampler2D texture4;  // [table3]
out vec4 frag_color;
void main() {
    vec4 c = vec4(0.5, 0.25, 0.125, 0.02);
    c = texture(texture2, v_texcoord0.xy);  // [fetch2d]
    vec4 v = texture(texture0, v_texcoord0.xyz);  // [fetch3d]
    c = v;  // [fetch3d]
    c = texture(texture2, vec2(v.g));  // [table1]
    c = texture(texture2, vec2(v.g));  // [table3]
    c += texture(texture3, vec2(v.b));  // [table3]
    c += texture(texture4, vec2(v.r));  // [table3]
    frag_color = vec4(c.rgb, 0.02 + 0.001 * c.a);
}

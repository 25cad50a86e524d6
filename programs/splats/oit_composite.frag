#version 330
// arbvis (new): GLSL twin of oit_composite.arbfp, weighted blended OIT's composite:
// texture0 the accumulation, texture1 the revealage (in r).
uniform sampler2D texture0;
uniform sampler2D texture1;
in vec4 v_texcoord0;
out vec4 FragColor;
void main() {
    vec4 accum = texture(texture0, v_texcoord0.xy);
    float reveal = texture(texture1, v_texcoord0.xy).r;
    FragColor = vec4(accum.rgb / max(accum.a, 1e-5), 1.0 - reveal);
}

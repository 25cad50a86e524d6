#version 330
// arbvis (new): GLSL twin of section/precise.arbfp, line for line.
in vec4 v_texcoord0;
uniform sampler2D texture0;
uniform sampler1D texture1;
uniform vec4 program_local[2];
out vec4 frag_color;
void main() {
    vec4 size = program_local[0];
    vec4 k = program_local[1];
    vec2 t = v_texcoord0.xy * size.xy - 0.5;
    vec2 lo = floor(t);
    vec2 f = fract(t);
    vec2 at = (lo + 0.5) * size.zw;
    vec4 a = texture(texture0, at);
    vec4 b = texture(texture0, at + vec2(size.z, 0.0));
    vec4 e = texture(texture0, at + size.zw);
    vec4 d = texture(texture0, at + vec2(0.0, size.w));
    a.xy = mix(a.xy, b.xy, f.x);
    d.xy = mix(d.xy, e.xy, f.x);
    a.xy = mix(a.xy, d.xy, f.y);
    if (a.y - 0.999999 < 0.0) discard;
    float level = clamp((a.x - k.x) * k.y, 0.0, 255.0);
    float entry = min(floor(level), 254.0);
    float g = level - entry;
    float s = entry * 0.00390625 + 0.001953125;
    vec4 c0 = texture(texture1, s);
    vec4 c1 = texture(texture1, s + 0.00390625);
    frag_color = vec4(mix(c0.xyz, c1.xyz, g) * k.z, k.z);
}

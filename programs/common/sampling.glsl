// arbvis (new): the linear texture reads of the precise 3D-opacity programs, joined at a
// template's sampling line (src/techniques/opacity3d/programs.rs). GL leaves the precision
// of GL_LINEAR to the driver: llvmpipe interpolates in f32, NVIDIA's texture units keep
// 8-bit weights (off by up to 1/512 of a texel step, 1e-2 after a steep table;
// src/gl/precision.rs measures it).
// Tags exact_volume, exact_tables, exact_steps: that texture's reads interpolate here, as
// GL_LINEAR with CLAMP_TO_EDGE defines it (texel space u = s * size - 0.5, the weights its
// fraction), from texelFetch and f32 mix; without the tag, the texture unit does.
// Texel space u = tc * size - 0.5: the texels below and above (clamped to the edge, as
// CLAMP_TO_EDGE) and the weights of the upper ones. 2D and 1D reads pass size 1 and
// coordinate 0.5 in the unused axes.
void corners(ivec3 size, vec3 tc, out ivec3 lo, out ivec3 hi, out vec3 f) {
    vec3 p = tc * vec3(size) - 0.5;
    vec3 b = floor(p);
    f = p - b;
    lo = clamp(ivec3(b), ivec3(0), size - 1);
    hi = clamp(ivec3(b) + 1, ivec3(0), size - 1);
}
vec4 lerp3(sampler3D s, vec3 tc) {
    ivec3 lo, hi;
    vec3 f;
    corners(textureSize(s, 0), tc, lo, hi, f);
    vec4 c00 = mix(texelFetch(s, lo, 0), texelFetch(s, ivec3(hi.x, lo.y, lo.z), 0), f.x);
    vec4 c10 = mix(texelFetch(s, ivec3(lo.x, hi.y, lo.z), 0), texelFetch(s, ivec3(hi.x, hi.y, lo.z), 0), f.x);
    vec4 c01 = mix(texelFetch(s, ivec3(lo.x, lo.y, hi.z), 0), texelFetch(s, ivec3(hi.x, lo.y, hi.z), 0), f.x);
    vec4 c11 = mix(texelFetch(s, ivec3(lo.x, hi.y, hi.z), 0), texelFetch(s, hi, 0), f.x);
    return mix(mix(c00, c10, f.y), mix(c01, c11, f.y), f.z);
}
vec4 lerp2(sampler2D s, vec2 tc) {
    ivec3 lo, hi;
    vec3 f;
    corners(ivec3(textureSize(s, 0), 1), vec3(tc, 0.5), lo, hi, f);
    vec4 c0 = mix(texelFetch(s, lo.xy, 0), texelFetch(s, ivec2(hi.x, lo.y), 0), f.x);
    vec4 c1 = mix(texelFetch(s, ivec2(lo.x, hi.y), 0), texelFetch(s, hi.xy, 0), f.x);
    return mix(c0, c1, f.y);
}
vec4 lerp1(sampler1D s, float tc) {
    ivec3 lo, hi;
    vec3 f;
    corners(ivec3(textureSize(s, 0), 1, 1), vec3(tc, 0.5, 0.5), lo, hi, f);
    return mix(texelFetch(s, lo.x, 0), texelFetch(s, hi.x, 0), f.x);
}
vec4 volume_at(sampler3D s, vec3 tc) { return textureLod(s, tc, 0.0); }  // [!exact_volume]
vec4 volume_at(sampler3D s, vec3 tc) { return lerp3(s, tc); }  // [exact_volume]
vec4 table_at(sampler2D s, vec2 tc) { return textureLod(s, tc, 0.0); }  // [!exact_tables]
vec4 table_at(sampler2D s, vec2 tc) { return lerp2(s, tc); }  // [exact_tables]
vec4 step_at(sampler2D s, vec2 tc) { return textureLod(s, tc, 0.0); }  // [!exact_steps]
vec4 step_at(sampler2D s, vec2 tc) { return lerp2(s, tc); }  // [exact_steps]
vec4 step_at(sampler1D s, float tc) { return textureLod(s, tc, 0.0); }  // [!exact_steps]
vec4 step_at(sampler1D s, float tc) { return lerp1(s, tc); }  // [exact_steps]

// arbvis clip (INDEX-DATA, precise: one MAD; see multires_offset.arbfp).
uniform sampler3D texture7;
uniform sampler3D texture8;
float clip_value(vec3 p) {
    vec4 idx = texture(texture7, p * program_local[10].xyz);
    if (abs(idx.w - 0.5) >= 0.25) return idx.w;
    return texture(texture8, p * program_local[11].xyz + idx.xyz).r;
}

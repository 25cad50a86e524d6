// arbvis clip (INDEX-DATA, faithful: the seed's coordinate formula; see
// multires_slot_centre.arbfp).
uniform sampler3D texture7;
uniform sampler3D texture8;
float clip_value(vec3 p) {
    vec4 idx = texture(texture7, p * program_local[10].xyz);
    if (abs(idx.w - 0.5) >= 0.25) return idx.w;
    return texture(texture8, idx.xyz + (p - (floor(p * program_local[12].xyz) + 0.5) * program_local[13].xyz) * program_local[11].xyz).r;
}

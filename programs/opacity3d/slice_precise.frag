#version 330
// arbvis (new): GLSL twin of opacity3d/slice_precise.arbfp, statement for statement, with
// the same tags (a line ending in a bracketed list of tags is kept only when the scene has
// all of them) and the same channel placeholders @1 @2 @3. See the ARB text for the maths.
in vec4 v_texcoord0;
uniform sampler3D texture0;
uniform sampler2D texture2;
uniform sampler2D texture3;  // [secondary]
uniform sampler2D texture4;  // [tertiary]
uniform vec4 program_local[22];
out vec4 frag_color;
// @sampling
void main() {
    vec4 correction = program_local[4];
    vec4 lookup = program_local[5];
    vec3 size = program_local[6].xyz;
    vec3 half_size = program_local[7].xyz;
    vec3 ray = program_local[8].xyz;
    vec3 axis = program_local[9].xyz;
    // The sample: the interpolated texture coordinate, or (pixel_points: a rasterizer that
    // interpolates from vertices snapped to its sub-pixel grid moves it by up to 1/512
    // pixel) the pixel's centre unprojected at the slice's depth, constant on a
    // view-aligned slice.
    vec3 tc = v_texcoord0.xyz;  // [!pixel_points]
    vec4 ndc = vec4(gl_FragCoord.xyz, 1.0) * program_local[16] + program_local[17];  // [pixel_points]
    vec4 h_p = vec4(dot(program_local[18], ndc), dot(program_local[19], ndc), dot(program_local[20], ndc), dot(program_local[21], ndc));  // [pixel_points]
    vec3 tc = (h_p.xyz / h_p.w + half_size) / size;  // [pixel_points]
    vec3 p = tc * size - half_size;
    vec4 v = volume_at(texture0, tc);
    vec4 coord = v * lookup.x + lookup.y;
    vec4 lut = table_at(texture2, vec2(coord.@1));
    vec4 col = program_local[1] * lut;
    lut = table_at(texture3, vec2(coord.@2));  // [secondary]
    col = program_local[2] * lut + col;  // [sum secondary]
    col = col * (program_local[2] * lut);  // [product secondary]
    lut = table_at(texture4, vec2(coord.@3));  // [tertiary]
    col = program_local[3] * lut + col;  // [sum tertiary]
    col = col * (program_local[3] * lut);  // [product tertiary]
    col = clamp(col * lookup.z, 0.0, 1.0);  // [sum]
    col = clamp(col, 0.0, 1.0);  // [product]
    vec3 q = p * ray;  // [orthographic]
    vec3 w = axis;  // [orthographic]
    float spacing = correction.y;  // [orthographic]
    vec3 dir = normalize(p - ray);  // [perspective]
    float spacing = correction.y / abs(dot(dir, axis));  // [perspective]
    vec3 q = mix(p, -p, lessThan(dir, vec3(0.0)));  // [perspective]
    vec3 w = 1.0 / max(abs(dir), vec3(1e-20));  // [perspective]
    vec3 back3 = (half_size + q) * w;
    vec3 fwd3 = (half_size - q) * w;
    float back = min(min(back3.x, back3.y), back3.z);
    float fwd = min(min(fwd3.x, fwd3.y), fwd3.z);
    back = back < 2.0 * spacing ? back : spacing;
    fwd = fwd < 2.0 * spacing ? fwd : spacing;
    float k = (back + fwd) * correction.x + correction.z;
    frag_color = vec4(col.xyz, 1.0 - pow(1.0 - col.w, k));
}

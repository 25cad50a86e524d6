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
    // pixel) where the pixel's own ray meets the slice's plane (the interpolated point's,
    // normal to the view direction or axis): the ray from the pixel's centre unprojected
    // onto the near and far planes (locals 16, 17: window position to NDC; 18..21: the
    // inverse view-projection's rows).
    vec3 tc = v_texcoord0.xyz;  // [!pixel_points]
    vec2 ndc = gl_FragCoord.xy * program_local[16].xy + program_local[17].xy;  // [pixel_points]
    mat4 inv = transpose(mat4(program_local[18], program_local[19], program_local[20], program_local[21]));  // [pixel_points]
    vec4 ray_near = inv * vec4(ndc, -1.0, 1.0);  // [pixel_points]
    vec4 ray_far = inv * vec4(ndc, 1.0, 1.0);  // [pixel_points]
    vec3 o = ray_near.xyz / ray_near.w;  // [pixel_points]
    vec3 d = ray_far.xyz / ray_far.w - o;  // [pixel_points]
    vec3 n = d;  // [pixel_points orthographic]
    vec3 n = axis;  // [pixel_points perspective]
    vec3 on_slice = v_texcoord0.xyz * size - half_size;  // [pixel_points]
    vec3 tc = (o + d * (dot(on_slice - o, n) / dot(d, n)) + half_size) / size;  // [pixel_points]
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

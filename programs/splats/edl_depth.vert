#version 330
// arbvis (new): eye-dome lighting's depth pass (precise splats, `edl > 0`): every point as a
// round sprite of its splat's size (the seed's rule, as precise.vert), its view distance
// (v_z, the row in vertex_local[8]) written by the nearest fragment (depth test LESS).
// vertex_local[0..3]: the transform rows; [4]: the eye (xyz) and 1 in perspective;
// [6]: (point size, factor, 0, 0); [8]: the view-distance row; [10]: (smallest size,
// largest size, 0, 0). GLSL only (with the tiles it serves).
layout(location = 0) in vec3 aPos;
layout(location = 4) in float aScale;
uniform vec4 vertex_local[11];
out float v_z;
// 0 for a point whose centre lies outside the clip volume (dropped whole, as precise.vert).
flat out float v_inside;
void main() {
    vec4 p = vec4(aPos, 1.0);
    gl_Position = vec4(dot(vertex_local[0], p), dot(vertex_local[1], p),
                       dot(vertex_local[2], p), dot(vertex_local[3], p));
    bool perspective = vertex_local[4].w > 0.5;
    vec3 d = aPos - vertex_local[4].xyz;
    float dd = (perspective ? 1.0 : 0.0) * (dot(d, d) - 1.0) + 1.0;
    float size = vertex_local[6].x * inversesqrt(dd) * vertex_local[6].y * aScale;
    if (!isnan(size)) size = clamp(size, vertex_local[10].x, vertex_local[10].y);
    gl_PointSize = size;
    v_z = dot(vertex_local[8], p);
    vec4 clip = gl_Position;
    v_inside = (clip.w > 0.0 && all(lessThanEqual(abs(clip.xyz), vec3(clip.w)))) ? 1.0 : 0.0;
}

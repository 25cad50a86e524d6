#version 330
// arbvis: the splat vertex stage (seed 004's vertex shader, with arbvis's uniforms).
// The seed's size rule as written: gl_PointSize = pointSize / distance(aPos, cameraPos)
// * factor (perspective); orthographic views have no camera distance: pointSize * factor.
// Lighting (Phong with a light at the eye, the seed's fix applied: normals facing away
// are flipped) is computed per point: v_light = (ambient + diffuse term, specular term).
// vertex_local[0..3]: ModelViewProj rows; [4]: cameraPos (xyz), w = 1 perspective;
// [5]: view direction (orthographic); [6]: (pointSize, factor, lighting on, 0);
// [7]: Phong (ambient, diffuse, specular, shininess); [8]: the row giving weighted blended
// OIT's view distance z (dot(vertex_local[8], p), see splats::oit).
// ARB twin: splat.arbvp.
layout(location = 0) in vec3 aPos;
layout(location = 1) in vec3 aColor;
layout(location = 2) in float aValue;
layout(location = 3) in vec3 aNormal;
uniform vec4 vertex_local[9];
out vec3 v_color;
out float v_value;
out vec2 v_light;
out float v_z;
void main() {
    vec4 p = vec4(aPos, 1.0);
    gl_Position = vec4(dot(vertex_local[0], p), dot(vertex_local[1], p),
                       dot(vertex_local[2], p), dot(vertex_local[3], p));
    bool perspective = vertex_local[4].w > 0.5;
    vec3 cameraPos = vertex_local[4].xyz;
    float pointSize = vertex_local[6].x;
    float factor = vertex_local[6].y;
    if (perspective) {
        float distanceToCamera = distance(aPos, cameraPos);
        gl_PointSize = pointSize / distanceToCamera * factor;
    } else {
        gl_PointSize = pointSize * factor;
    }
    v_color = aColor;
    v_value = aValue;
    v_z = dot(vertex_local[8], p);
    v_light = vec2(1.0, 0.0);
    if (vertex_local[6].z > 0.5) {
        vec3 v = normalize(perspective ? cameraPos - aPos : -vertex_local[5].xyz);
        vec3 n = aNormal;
        if (dot(n, v) < 0.0) n = -n;
        float diffuse = max(dot(n, v), 0.0);
        vec3 r = 2.0 * dot(n, v) * n - v;
        float specular = pow(max(dot(r, v), 0.0), vertex_local[7].w);
        v_light = vec2(vertex_local[7].x + vertex_local[7].y * diffuse,
                       vertex_local[7].z * specular);
    }
}

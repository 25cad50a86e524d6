#version 330
// arbvis: GLSL twin of cellproj/orthographic.arbvp (t_i per vertex, D constant).
// vertex_local[0..3]: ModelViewProj rows; vertex_local[4]: D in object space.
layout(location = 0) in vec4 position;
layout(location = 1) in float scalar;
layout(location = 2) in vec3 vertex3;
layout(location = 3) in vec3 normal0;
layout(location = 4) in vec3 normal1;
layout(location = 5) in vec3 normal2;
layout(location = 6) in vec3 gradient;
uniform vec4 vertex_local[5];
out float v_sf;
out vec3 v_ti;
out float v_gd;
void main() {
    gl_Position = vec4(dot(vertex_local[0], position), dot(vertex_local[1], position),
                       dot(vertex_local[2], position), dot(vertex_local[3], position));
    v_sf = clamp(scalar, 0.0, 1.0);
    vec3 D = vertex_local[4].xyz;
    vec3 aux1 = vertex3 - position.xyz;
    v_ti = vec3(dot(aux1, normal0) * (1.0 / dot(D, normal0)),
                dot(aux1, normal1) * (1.0 / dot(D, normal1)),
                dot(aux1, normal2) * (1.0 / dot(D, normal2)));
#ifdef GUARDED_EXIT
    // The volume's precise `table`: a plane the ray enters through (D.N <= 0, normals
    // outward) is never its exit (volume_orthographic.frag).
    v_ti = mix(v_ti, vec3(1e30), lessThanEqual(vec3(dot(D, normal0), dot(D, normal1),
                                                    dot(D, normal2)), vec3(0.0)));
#endif
    v_gd = dot(gradient, D);
}

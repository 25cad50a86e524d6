#version 330
// arbvis, precise `table` with the exit per fragment: each tetrahedron's four corners
// carry the cell's four face planes and scalar gradient, passed on `flat`; only the
// position and the scalar vary over a triangle. vertex_local[0..3]: ModelViewProj rows.
layout(location = 0) in vec4 position;
layout(location = 1) in float scalar;
layout(location = 2) in vec4 plane0;
layout(location = 3) in vec4 plane1;
layout(location = 4) in vec4 plane2;
layout(location = 5) in vec4 plane3;
layout(location = 6) in vec3 gradient;
uniform vec4 vertex_local[4];
out vec3 v_position;
out float v_scalar;
flat out vec4 v_plane0, v_plane1, v_plane2, v_plane3;
flat out vec3 v_gradient;
void main() {
    gl_Position = vec4(dot(vertex_local[0], position), dot(vertex_local[1], position),
                       dot(vertex_local[2], position), dot(vertex_local[3], position));
    v_position = position.xyz;
    v_scalar = scalar;
    v_plane0 = plane0;
    v_plane1 = plane1;
    v_plane2 = plane2;
    v_plane3 = plane3;
    v_gradient = gradient;
}

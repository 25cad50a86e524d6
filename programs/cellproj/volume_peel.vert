#version 330
// arbvis (new, issue 16): the boundary faces of the mesh for the precise volume's entry
// layers: object position, the tetrahedron the face belongs to, and the face's plane
// (normal, offset: the tetrahedra texture's values).
// vertex_local[0..3]: ModelViewProj rows.
layout(location = 0) in vec3 position;
layout(location = 1) in float tet;
layout(location = 2) in vec4 plane;
uniform vec4 vertex_local[4];
out vec3 v_pos;
flat out float v_tet;
flat out vec4 v_plane;
void main() {
    vec4 p = vec4(position, 1.0);
    gl_Position = vec4(dot(vertex_local[0], p), dot(vertex_local[1], p),
                       dot(vertex_local[2], p), dot(vertex_local[3], p));
    v_pos = position;
    v_tet = tet;
    v_plane = plane;
}

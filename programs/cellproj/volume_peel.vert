#version 330
// arbvis (new, issue 16): the boundary faces of the mesh for the precise volume's entry
// layers: object position and the tetrahedron the face belongs to.
// vertex_local[0..3]: ModelViewProj rows.
layout(location = 0) in vec3 position;
layout(location = 1) in float tet;
uniform vec4 vertex_local[4];
out vec3 v_pos;
flat out float v_tet;
void main() {
    vec4 p = vec4(position, 1.0);
    gl_Position = vec4(dot(vertex_local[0], p), dot(vertex_local[1], p),
                       dot(vertex_local[2], p), dot(vertex_local[3], p));
    v_pos = position;
    v_tet = tet;
}

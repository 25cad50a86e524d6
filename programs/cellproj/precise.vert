#version 330
// arbvis (new): the precise cell-projection vertex stage. Passes the seed's inputs on,
// with the scalar as a float (no COLOR0 clamp). vertex_local[0..3]: ModelViewProj rows.
layout(location = 0) in vec4 position;
layout(location = 1) in float scalar;
layout(location = 2) in vec3 vertex3;
layout(location = 3) in vec3 normal0;
layout(location = 4) in vec3 normal1;
layout(location = 5) in vec3 normal2;
layout(location = 6) in vec3 gradient;
uniform vec4 vertex_local[4];
out float v_sf;
out vec3 v_pos, v_vertex3, v_gradient;
flat out vec3 v_normal0, v_normal1, v_normal2;
void main() {
    gl_Position = vec4(dot(vertex_local[0], position), dot(vertex_local[1], position),
                       dot(vertex_local[2], position), dot(vertex_local[3], position));
    v_sf = scalar;
    v_pos = position.xyz;
    v_vertex3 = vertex3;
    v_gradient = gradient;
    v_normal0 = normal0;
    v_normal1 = normal1;
    v_normal2 = normal2;
}

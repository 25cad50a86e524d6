#version 330
// arbvis (new): GLSL twin of surface/gouraud.arbvp (the same locals and attributes).
layout(location = 0) in vec4 position;
layout(location = 1) in vec4 normal;
layout(location = 2) in vec4 colour;
uniform vec4 vertex_local[6];
out vec4 v_colour;
void main() {
    gl_Position = vec4(dot(vertex_local[0], position), dot(vertex_local[1], position),
                       dot(vertex_local[2], position), dot(vertex_local[3], position));
    vec4 k = vertex_local[5];
    float d = abs(dot(normalize(normal.xyz), vertex_local[4].xyz)) * k.y + k.x;
    v_colour = vec4(colour.xyz * d * k.z, k.z);
}

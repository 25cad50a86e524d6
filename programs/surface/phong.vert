#version 330
// arbvis (new): GLSL twin of surface/phong.arbvp.
layout(location = 0) in vec4 position;
layout(location = 1) in vec4 normal;
layout(location = 2) in vec4 colour;
uniform vec4 vertex_local[4];
out vec4 v_normal;
out vec4 v_colour;
void main() {
    gl_Position = vec4(dot(vertex_local[0], position), dot(vertex_local[1], position),
                       dot(vertex_local[2], position), dot(vertex_local[3], position));
    v_normal = normal;
    v_colour = colour;
}

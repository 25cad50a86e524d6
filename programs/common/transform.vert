#version 330
// arbvis (new): GLSL twin of common/transform.arbvp. vertex_local[0..3] are the rows of
// the model-view-projection matrix, exactly as the ARB program's program.local[0..3].
layout(location = 0) in vec4 position;
layout(location = 1) in vec4 texcoord0;
uniform vec4 vertex_local[4];
out vec4 v_texcoord0;
void main() {
    gl_Position = vec4(dot(vertex_local[0], position), dot(vertex_local[1], position),
                       dot(vertex_local[2], position), dot(vertex_local[3], position));
    v_texcoord0 = texcoord0;
}

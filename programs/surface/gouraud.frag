#version 330
// arbvis (new): GLSL twin of surface/gouraud.arbfp.
in vec4 v_colour;
out vec4 frag_color;
void main() {
    frag_color = v_colour;
}

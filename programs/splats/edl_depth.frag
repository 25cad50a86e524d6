#version 330
// arbvis (new): eye-dome lighting's depth pass: the splat's disc (gl_PointCoord within the
// inscribed circle) writes its view distance, the nearest kept by the depth test.
in float v_z;
flat in float v_inside;
out vec4 FragColor;
void main() {
    if (v_inside < 0.5) discard;
    vec2 d = gl_PointCoord - vec2(0.5);
    if (dot(d, d) > 0.25) discard;
    FragColor = vec4(v_z, 0.0, 0.0, 1.0);
}

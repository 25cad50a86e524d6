#version 330
// arbvis (new, issue 16): one entry layer of the precise volume (depth peeling of the
// boundary faces through which rays enter the mesh, Everitt 2001). The nearest entry
// (depth test LESS on a fresh depth buffer) beyond the previous layer's: the fragment
// writes (its tetrahedron, the entry's distance along the pixel's ray, where the ray meets
// the face's plane). A non-convex mesh is entered several times along one ray; layer k
// holds the k-th entry.
// program_local[0..3]: inverse ModelViewProj rows; [4]: viewport (width, height,
// corner x, corner y); [5].x: 1 when texture3 holds the previous layer.
uniform sampler2D texture3;
uniform vec4 program_local[6];
in vec3 v_pos;
flat in float v_tet;
flat in vec4 v_plane;
out vec4 color;

void main() {
    mat4 inv = transpose(mat4(program_local[0], program_local[1], program_local[2],
                              program_local[3]));
    vec2 ndc = 2.0 * (gl_FragCoord.xy - program_local[4].zw) / program_local[4].xy - 1.0;
    vec4 n = inv * vec4(ndc, -1.0, 1.0);
    vec4 f = inv * vec4(ndc, 1.0, 1.0);
    vec3 o = n.xyz / n.w;
    vec3 d = normalize(f.xyz / f.w - o);
    // The entry along the pixel's own ray: its intersection with the face's plane (an
    // interpolated position moves with the rasterizer's vertex snapping, by up to 1/512
    // pixel, which a face seen edge-on turns into a long way along the ray).
    float dn = dot(v_plane.xyz, d);
    float t = abs(dn) > 1e-7 ? (v_plane.w - dot(v_plane.xyz, o)) / dn : dot(v_pos - o, d);
    if (program_local[5].x > 0.5) {
        vec4 prev = texelFetch(texture3, ivec2(gl_FragCoord.xy - program_local[4].zw), 0);
        if (prev.x < 0.0 || t <= prev.y + 1e-5 * (1.0 + abs(prev.y))) discard;
    }
    color = vec4(v_tet, t, 0.0, 1.0);
}

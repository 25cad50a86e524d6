#version 330
// arbvis (new): eye-dome lighting (Boucheny 2009, as CloudCompare and Potree shade clouds
// without normals): each pixel's view distance z against its 8 neighbours at `radius`
// pixels, response = sum of max(0, log2(z) - log2(z_n)) / 8 over neighbours that hold a
// point, shade = exp(-300 strength response); drawn over the splats' picture with the
// blend ZERO, SRC_COLOR, so each colour is multiplied by its shade (alpha unchanged).
// Pixels without a point are left as they are. texture0: the depth pass (r = view
// distance, 0 where no point); program_local[0]: (strength, radius, 0, 0); [1].xy: the
// viewport's corner in window coordinates (0 offscreen).
uniform sampler2D texture0;
uniform vec4 program_local[2];
out vec4 FragColor;
void main() {
    ivec2 p = ivec2(gl_FragCoord.xy - program_local[1].xy);
    ivec2 size = textureSize(texture0, 0);
    float z = texelFetch(texture0, p, 0).r;
    if (!(z > 0.0)) {
        FragColor = vec4(1.0);
        return;
    }
    float r = program_local[0].y;
    float response = 0.0;
    for (int k = 0; k < 8; k++) {
        float a = 0.785398163 * float(k);
        ivec2 q = clamp(p + ivec2(round(r * vec2(cos(a), sin(a)))), ivec2(0), size - 1);
        float zn = texelFetch(texture0, q, 0).r;
        if (zn > 0.0) response += max(0.0, log2(z) - log2(zn));
    }
    float shade = exp(-300.0 * program_local[0].x * response / 8.0);
    FragColor = vec4(vec3(shade), 1.0);
}

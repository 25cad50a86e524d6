#version 330
// arbvis (new): the splats composited by gather, per pixel, from tile lists (precise mode;
// splats::tiles builds the lists on the CPU, splats::tiled draws this over a full-screen
// quad). The same splats as precise.frag draws as GL_POINTS: a pixel is covered when
// its centre lies in the half-open square of side `size` around the splat's window
// position and within the inscribed circle (n_dist <= 1); alpha = point alpha x the
// precise footprint, clamped; colour clamped to [0, 1] as the f64 reference takes it.
// The list of the pixel's tile holds its splats back to front; the pixel walks it from
// the end and composites front to back (C += T a c, T *= 1 - a) and stops once T < 2^-16 (what is left
// could change no channel by more than 2^-16). Output (C, 1 - T), blended ONE,
// ONE_MINUS_SRC_ALPHA over the cleared target: C + T dst, as back-to-front "over" gives.
// texture0: tile start offsets (R32UI, tiles + 1 words, row-major tiles, 4096 per row);
// texture1: list entries (RGBA32UI: window x, y and size as f32 bits, point index);
// texture2: point colours (RGBA32F by point index).
// program_local[0]: (tile size in pixels, tiles across, kernel: 1 Gaussian / 0 smoothstep,
// Gaussian width); [1].xy: the viewport's corner in window coordinates (0 offscreen).
uniform usampler2D texture0;
uniform usampler2D texture1;
uniform sampler2D texture2;
uniform vec4 program_local[2];
out vec4 FragColor;

const int ROW = 4096;
const float FLOOR = 1.0 / 65536.0;

ivec2 at(uint k) {
    return ivec2(int(k % uint(ROW)), int(k / uint(ROW)));
}

float footprint(float n_dist) {
    if (program_local[0].z > 0.5) {
        float w = program_local[0].w;
        return w > 0.0 ? exp(-n_dist * n_dist / (2.0 * w)) : (n_dist == 0.0 ? 1.0 : 0.0);
    }
    return smoothstep(0.0, 1.0, 1.0 - n_dist);
}

void main() {
    int tile_size = int(program_local[0].x);
    int across = int(program_local[0].y);
    vec2 centre = gl_FragCoord.xy - program_local[1].xy;
    ivec2 pixel = ivec2(centre);
    uint tile = uint((pixel.y / tile_size) * across + pixel.x / tile_size);
    uint first = texelFetch(texture0, at(tile), 0).r;
    uint last = texelFetch(texture0, at(tile + 1u), 0).r;
    vec3 colour = vec3(0.0);
    float transmittance = 1.0;
    for (uint k = last; k > first && transmittance >= FLOOR; k--) {
        uvec4 e = texelFetch(texture1, at(k - 1u), 0);
        vec2 d = centre - vec2(uintBitsToFloat(e.x), uintBitsToFloat(e.y));
        float half_size = 0.5 * uintBitsToFloat(e.z);
        if (any(lessThan(d, vec2(-half_size))) || any(greaterThanEqual(d, vec2(half_size))))
            continue;
        float n_dist = length(d) / half_size;
        if (n_dist > 1.0) continue;
        vec4 point = texelFetch(texture2, at(e.w), 0);
        float alpha = clamp(point.a * footprint(n_dist), 0.0, 1.0);
        if (isnan(alpha)) alpha = 0.0;
        colour += transmittance * alpha * clamp(point.rgb, 0.0, 1.0);
        transmittance *= 1.0 - alpha;
    }
    FragColor = vec4(colour, 1.0 - transmittance);
}

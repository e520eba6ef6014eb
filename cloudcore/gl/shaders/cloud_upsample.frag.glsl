#version 400 core
// The reduced cloud pass (premultiplied colour, alpha the clouds' opacity) over the full-resolution world: each
// pixel takes the four reduced texels around it, weighed by their bilinear share and by how near the depth each
// was tested against (the nearest of its block) is to the pixel's own world depth, so that terrain, objects and the
// horizon crossing clouds keep their edges; where none is near, the one nearest in depth of the nine around its
// own texel, whole.  Drawn over the screen triangle of world.vert, blended ONE, ONE_MINUS_SRC_ALPHA.  Its twin, and
// why: cloudcore/maths/depth_upsampling.py.
//
// llvmpipe pays each pixel's fetches and arithmetic, and most pixels need neither: where the four texels were
// tested against the pixel's own depth (the sky's, mostly) the weights are the bilinear shares, one filtered fetch;
// where the texels near the pixel's depth hold no cloud, nothing is added.

uniform sampler2D clouds;       // the reduced pass's colour, filtered linearly, clamped to its edge
uniform sampler2D cloud_depth;  // the depth its texels were tested against, clamped to its edge
uniform sampler2D world_depth;  // the screen's
uniform ivec2 screen_size;
uniform ivec2 reduced_size;
uniform float near_m;
uniform float far_m;
uniform float tolerance;         // DEPTH_TOLERANCE
uniform float behind_tolerance;  // BEHIND_TOLERANCE
uniform float no_match_weight;   // NO_MATCH_WEIGHT

out vec4 frag_colour;

float distance_of(float depth)
{
    return near_m * far_m / (far_m - clamp(depth, 0.0, 1.0) * (far_m - near_m));
}

vec4 distances_of(vec4 depth)
{
    return near_m * far_m / (far_m - clamp(depth, 0.0, 1.0) * (far_m - near_m));
}

void main()
{
    ivec2 pixel = ivec2(gl_FragCoord.xy);
    vec2 uv = gl_FragCoord.xy / vec2(screen_size);  // the pixel's centre: its four texels' footprint
    float depth = texelFetch(world_depth, pixel, 0).r;
    // the 2x2 texels of a bilinear fetch at uv, in textureGather's order: (0, 1), (1, 1), (1, 0), (0, 0)
    vec4 tested = textureGather(cloud_depth, uv);
    if (all(equal(tested, vec4(depth)))) {
        frag_colour = texture(clouds, uv);
        return;
    }
    vec2 at = uv * vec2(reduced_size) - 0.5;
    vec2 base = floor(at);
    vec2 f = at - base;
    float z = distance_of(depth);
    vec4 texel_z = distances_of(tested);
    vec4 apart = abs(texel_z - z) / min(texel_z, vec4(z));
    vec4 scaled = apart / mix(vec4(tolerance), vec4(behind_tolerance), greaterThan(texel_z, vec4(z)));
    vec4 shares = vec4((1.0 - f.x) * f.y, f.x * f.y, f.x * (1.0 - f.y), (1.0 - f.x) * (1.0 - f.y));
    vec4 weights = shares * exp(-scaled * scaled);
    float total = dot(weights, vec4(1.0));
    if (total > no_match_weight) {
        if (dot(weights, textureGather(clouds, uv, 3)) == 0.0)
            discard;  // no cloud where the weights are
        ivec2 low = clamp(ivec2(base), ivec2(0), reduced_size - 1);
        ivec2 high = clamp(ivec2(base) + 1, ivec2(0), reduced_size - 1);
        frag_colour = (weights.x * texelFetch(clouds, ivec2(low.x, high.y), 0)
                       + weights.y * texelFetch(clouds, high, 0)
                       + weights.z * texelFetch(clouds, ivec2(high.x, low.y), 0)
                       + weights.w * texelFetch(clouds, low, 0)) / total;
        return;
    }
    // none near: the pixel's own texel or one of the eight around it, whichever is nearest in depth
    ivec2 own = ivec2(floor(at + 0.5));
    float best = 3.0e38;  // more than any difference of distances
    ivec2 nearest = own;
    for (int y = -1; y <= 1; ++y)
        for (int x = -1; x <= 1; ++x) {
            ivec2 texel = clamp(own + ivec2(x, y), ivec2(0), reduced_size - 1);
            float texel_z = distance_of(texelFetch(cloud_depth, texel, 0).r);
            float texel_apart = abs(texel_z - z) / min(texel_z, z);
            if (texel_apart < best) {
                best = texel_apart;
                nearest = texel;
            }
        }
    frag_colour = texelFetch(clouds, nearest, 0);
}

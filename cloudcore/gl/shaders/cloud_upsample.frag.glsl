#version 330 core
// The reduced cloud pass (premultiplied colour, alpha the clouds' opacity) over the full-resolution world: each
// pixel takes the four reduced texels around it, weighed by their bilinear share and by how near the depth each
// was tested against (the nearest of its block) is to the pixel's own world depth, so that terrain, objects and the
// horizon crossing clouds keep their edges; where none is near, the one nearest in depth of the nine around its
// own texel, whole.  Drawn over the
// screen triangle of world.vert, blended ONE, ONE_MINUS_SRC_ALPHA.  Its twin, and why: cloudcore/depth_upsampling.py.

uniform sampler2D clouds;       // the reduced pass's colour
uniform sampler2D cloud_depth;  // the depth its texels were tested against
uniform sampler2D world_depth;  // the screen's
uniform ivec2 screen_size;
uniform ivec2 reduced_size;
uniform float near_m;
uniform float far_m;
uniform float tolerance;       // DEPTH_TOLERANCE
uniform float behind_tolerance;  // BEHIND_TOLERANCE
uniform float no_match_weight;  // NO_MATCH_WEIGHT

out vec4 frag_colour;

float distance_of(float depth)
{
    return near_m * far_m / (far_m - clamp(depth, 0.0, 1.0) * (far_m - near_m));
}

void main()
{
    ivec2 pixel = ivec2(gl_FragCoord.xy);
    float z = distance_of(texelFetch(world_depth, pixel, 0).r);
    vec2 at = (vec2(pixel) + 0.5) * vec2(reduced_size) / vec2(screen_size) - 0.5;
    vec2 base = floor(at);
    vec2 f = at - base;
    vec4 summed = vec4(0.0);
    float total = 0.0;
    for (int corner = 0; corner < 4; ++corner) {
        ivec2 offset = ivec2(corner & 1, corner >> 1);
        ivec2 texel = clamp(ivec2(base) + offset, ivec2(0), reduced_size - 1);
        vec2 shares = mix(1.0 - f, f, vec2(offset));
        float texel_z = distance_of(texelFetch(cloud_depth, texel, 0).r);
        float apart = abs(texel_z - z) / min(texel_z, z);
        float scaled = apart / (texel_z > z ? behind_tolerance : tolerance);
        float weight = shares.x * shares.y * exp(-scaled * scaled);
        summed += weight * texelFetch(clouds, texel, 0);
        total += weight;
    }
    if (total > no_match_weight) {
        frag_colour = summed / total;
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
            float apart = abs(texel_z - z) / min(texel_z, z);
            if (apart < best) {
                best = apart;
                nearest = texel;
            }
        }
    frag_colour = texelFetch(clouds, nearest, 0);
}

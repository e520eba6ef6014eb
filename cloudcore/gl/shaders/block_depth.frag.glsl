#version 330 core
// The reduced cloud pass's depth: the nearest of the world's depths in the block of the screen's pixels that each
// texel covers (its pixels' centres), drawn over the screen triangle of world.vert into a depth-only target.  Why
// the nearest: cloudcore/maths/depth_upsampling.py, whose block_nearest_depth is its twin.

uniform sampler2D world_depth;  // the screen's
uniform ivec2 screen_size;
uniform ivec2 reduced_size;

void main()
{
    ivec2 texel = ivec2(gl_FragCoord.xy);
    ivec2 first = (texel * screen_size + reduced_size - 1) / reduced_size;
    ivec2 end = min(((texel + 1) * screen_size + reduced_size - 1) / reduced_size, screen_size);
    float nearest = 1.0;
    for (int y = first.y; y < end.y; ++y)
        for (int x = first.x; x < end.x; ++x)
            nearest = min(nearest, texelFetch(world_depth, ivec2(x, y), 0).r);
    gl_FragDepth = nearest;
}

#version 330 core
// Which tiles of the screen the reduced cloud pass's composite must draw: 1 where a texel that any pixel of the
// tile reads (its bilinear four, the nine around its own; two texels of margin) holds cloud, else 0.  One fragment
// a tile, over the screen triangle of world.vert into a target of a texel a tile; cloud_tiles.vert reads it.

uniform sampler2D clouds;  // the reduced pass's colour
uniform ivec2 screen_size;
uniform ivec2 reduced_size;
uniform int tile_pixels;

out float covered;

void main()
{
    ivec2 tile = ivec2(gl_FragCoord.xy);
    ivec2 first = max(tile * tile_pixels * reduced_size / screen_size - 2, ivec2(0));
    ivec2 end = min(((tile + 1) * tile_pixels * reduced_size + screen_size - 1) / screen_size + 2, reduced_size);
    float alpha = 0.0;
    for (int y = first.y; y < end.y; ++y)
        for (int x = first.x; x < end.x; ++x)
            alpha = max(alpha, texelFetch(clouds, ivec2(x, y), 0).a);
    covered = alpha > 0.0 ? 1.0 : 0.0;
}

#version 330 core
// The reduced cloud pass's composite laid over the tiles of the screen that hold cloud (cloud_tiles.frag's), one
// instance a tile, a triangle strip from gl_VertexID; a tile without cloud is sent outside the clip volume.  On
// llvmpipe a draw costs the loading and storing of every tile of the frame it touches, drawn or discarded: over the
// whole screen the composite cost more than the default view's whole cloud pass at full resolution.

uniform sampler2D tiles_covered;
uniform ivec2 screen_size;
uniform int tile_pixels;

void main()
{
    int tiles_across = (screen_size.x + tile_pixels - 1) / tile_pixels;
    ivec2 tile = ivec2(gl_InstanceID % tiles_across, gl_InstanceID / tiles_across);
    ivec2 corner = ivec2(gl_VertexID & 1, gl_VertexID >> 1);
    vec2 pixel = vec2(min((tile + corner) * tile_pixels, screen_size));
    bool drawn = texelFetch(tiles_covered, tile, 0).r > 0.5;
    gl_Position = drawn ? vec4(2.0 * pixel / vec2(screen_size) - 1.0, 0.0, 1.0) : vec4(2.0, 2.0, 2.0, 1.0);
}

// What tile_bin.comp.glsl makes of a draw's splats besides their tile lists, and volume_blend.comp.glsl
// composites from (included by both: cloudcore.gl.programs).

// the tiles with splats: a DispatchIndirectCommand of one group a tile (at most max_groups, the groups
// looping over the rest), their count, and the tiles, in no order; the command's y and z and the count
// start at 1, 1, 0 (cloudcore.gl.tile_binning)
layout(std430, binding = 8) buffer Occupied {
    uint groups_x;
    uint groups_y;
    uint groups_z;
    uint occupied_count;
    uint occupied[];
};

// per slot, the splat as the compositing reads it for each of its pixels
struct Disc {
    vec4 image;      // in pixels: the centre, 1 / half width, 1 / half height
    vec4 colour;     // premultiplied linear rgb, opacity
    vec4 centre_r2;  // relative to the eye, and the radius squared
};
layout(std430, binding = 14) buffer Discs { Disc discs[]; };

// the kernel's d squared at `pixel` (pixel centres whole numbers): its offset from the image's centre over the
// half sizes, the raster's interpolation over a quad that faces the image plane
float d2_at(Disc p, vec2 pixel)
{
    vec2 offset = (pixel - p.image.xy) * p.image.zw;
    return dot(offset, offset);
}

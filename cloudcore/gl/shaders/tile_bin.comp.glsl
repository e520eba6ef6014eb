#version 430 core
// The screen tiles of a draw's splats, made on the GPU, for the tiled compute pass that composites them
// (volume_blend.comp.glsl, as volumes or as the raster blends them): the numpy binning
// (cloudcore.light.volume_blending.screen_tiles) without the CPU.  The draw's instances are those
// splat_shade.comp.glsl made, far to near: a GPU-chosen draw's as many kept as its indirect command counts
// (six indices each), a draw sorted on the CPU all of them.  Three stages, chosen by the stage defined:
//   COUNT   per slot, the tiles its kept splat's disc can touch (0 for a slot not kept), into
//           pair_starts[slot] and added to the draw's total; a prefix sum over the slots then makes each
//           slot's count where its pairs start (cloudcore.gl.prefix_sum);
//   EMIT    per kept splat, one (slot, tile) pair a tile from where its pairs start, those within the
//           `room` of the buffers: the pairs in slot order, far to near, so that one stable radix sort by
//           tile leaves each tile's run far to near;
//   STARTS  over the pairs sorted by tile (the total's, at most the room's): where each tile's run starts
//           (tile_starts[t] to tile_starts[t + 1]), as ScreenTiles.starts, and the tiles with a run, as
//           ScreenTiles.occupied (in no order), with the indirect dispatch that composites them.
// The total stays on the GPU: the CPU gives the room, and reads the total after the frame (a total past
// the room left out the draw's nearest pairs: cloudcore.gl.tile_binning draws the frame again).
// A splat's image is bounded by its four corners' (it is a flat quad), one pixel wider on each side
// for rounding, and of that box's tiles only those its disc reaches (a quarter fewer pairs on the default
// view: the kernel is 0 past the disc).

layout(local_size_x = 64) in;

struct Instance {
    vec4 corners[4];  // relative to the eye; w: atlas cell (-1: Gaussian splat)
    vec4 colours[4];  // premultiplied linear rgb, opacity
};
layout(std430, binding = 3) readonly buffer Instances { Instance instances[]; };  // from the draw's first
layout(std430, binding = 6) readonly buffer Command { uint command[]; };
layout(std430, binding = 9) buffer Totals { uint totals[]; };  // the draw's at `total_at`
layout(std430, binding = 13) buffer PairStarts { uint pair_starts[]; };  // per slot
layout(std430, binding = 10) buffer PairSlots { uint pair_slots[]; };
layout(std430, binding = 11) buffer PairTiles { uint pair_tiles[]; };
layout(std430, binding = 12) writeonly buffer TileStarts { uint tile_starts[]; };
#include "binned_splats.glsl"

uniform uint slots;        // the draw's slots, kept or not
uniform uint count_at;     // its command's count in the command buffer (six a kept splat), or ALL_SLOTS
uniform mat4 view_rotation;
uniform mat4 projection;
uniform ivec2 size;        // pixels
uniform int tiles_across;
uniform int tiles_up;
uniform float near;
uniform uint total_at;     // where the draw's total of pairs is counted in `totals`
uniform uint room;         // EMIT, STARTS: the most pairs the buffers hold
uniform uint max_groups;   // STARTS: the most work groups a dispatch may ask for

const float TINY = 1e-30;
const uint ALL_SLOTS = 0xFFFFFFFFu;  // a draw whose slots are all kept (sorted on the CPU): no command

// The tiles splat j can touch: the box of its quad's image (first tile column, first row, last column, last
// row; empty when last < first), and the image itself in pixels: its centre, half width and half height
// (a plain splat's quad faces the image plane, so its image is a rectangle, the kernel's disc the ellipse
// inscribed in it, a circle on square pixels).  Behind the near plane, nothing: the quad's
// corners are at the splat's depth, so the raster clips it whole (a corner across the plane from the others
// is the rounding of an axis; the frustum keeps a sphere reaching past the plane).
struct Footprint {
    ivec4 box;
    vec4 image;
};

const Footprint NOWHERE = Footprint(ivec4(0, 0, -1, -1), vec4(0.0, 0.0, 1.0, 1.0));

Footprint footprint(uint j)
{
    vec2 low = vec2(3.0e38), high = vec2(-3.0e38);
    for (int k = 0; k < 4; ++k) {
        vec4 clip = projection * (view_rotation * vec4(instances[j].corners[k].xyz, 1.0));
        if (clip.w <= near)
            return NOWHERE;
        vec2 pixel = (clip.xy / clip.w * 0.5 + 0.5) * vec2(size) - 0.5;  // pixel centres are whole numbers
        low = min(low, pixel);
        high = max(high, pixel);
    }
    ivec2 first = ivec2(clamp(floor(low) - 1.0, vec2(0.0), vec2(size)));
    ivec2 last = ivec2(clamp(ceil(high) + 1.0, vec2(-1.0), vec2(size - 1)));
    if (any(lessThan(last, first)))
        return NOWHERE;
    vec4 image = vec4(0.5 * (low + high), 0.5 * (high - low));
    return Footprint(ivec4(first / TILE_PIXELS, last / TILE_PIXELS), image);
}

// the first and last columns of the footprint's tiles in `row` whose pixel centres its disc reaches (the
// tile's pixel nearest the disc's centre within its radius); empty when last < first
ivec2 columns_in_row(Footprint f, int row)
{
    vec2 centre = f.image.xy;
    float radius = max(f.image.z, f.image.w) + 1.0;  // a pixel wider, for rounding
    float nearest_y = clamp(centre.y, float(row * TILE_PIXELS), float(row * TILE_PIXELS + TILE_PIXELS - 1));
    float across2 = radius * radius - (nearest_y - centre.y) * (nearest_y - centre.y);
    if (across2 < 0.0)
        return ivec2(0, -1);
    float across = sqrt(across2);
    int first = int(ceil((centre.x - across - float(TILE_PIXELS - 1)) / float(TILE_PIXELS)));
    int last = int(floor((centre.x + across) / float(TILE_PIXELS)));
    return ivec2(max(first, f.box.x), min(last, f.box.z));
}

void run(uint i, uint items)
{
#ifdef STARTS
    uint tile = pair_tiles[i];
    uint before = i == 0u ? 0u : pair_tiles[i - 1u] + 1u;
    for (uint t = before; t <= tile; ++t)
        tile_starts[t] = i;
    if (before <= tile) {  // the first of its tile's run
        uint at = atomicAdd(occupied_count, 1u);
        occupied[at] = tile;
        atomicMax(groups_x, min(at + 1u, max_groups));
    }
    if (i == items - 1u)  // the last pair: the tiles after its own start past the pairs
        for (uint t = tile + 1u; t <= uint(tiles_across * tiles_up); ++t)
            tile_starts[t] = items;
#else
    uint kept = count_at == ALL_SLOTS ? slots : command[count_at] / 6u;
    Footprint f = i < kept ? footprint(i) : NOWHERE;
#ifdef COUNT
    // what the compositing reads of the splat for each of its pixels
    Instance splat = instances[i];
    vec3 centre = 0.5 * (splat.corners[0].xyz + splat.corners[3].xyz);
    vec3 right = 0.5 * (splat.corners[1].xyz - splat.corners[0].xyz);  // the radius along the splat's right
    vec4 image = vec4(f.image.xy, 1.0 / max(f.image.zw, vec2(TINY)));
    discs[i] = Disc(image, splat.colours[0], vec4(centre, dot(right, right)));
    uint covered = 0u;
    for (int row = f.box.y; row <= f.box.w; ++row) {
        ivec2 columns = columns_in_row(f, row);
        covered += uint(max(columns.y - columns.x + 1, 0));
    }
    pair_starts[i] = covered;
    atomicAdd(totals[total_at], covered);
#else
    uint at = pair_starts[i];
    for (int row = f.box.y; row <= f.box.w; ++row) {
        ivec2 columns = columns_in_row(f, row);
        for (int column = columns.x; column <= columns.y; ++column) {
            if (at >= room)
                return;
            pair_slots[at] = i;
            pair_tiles[at] = uint(row * tiles_across + column);
            ++at;
        }
    }
#endif
#endif
}

// as many invocations as the GL dispatches, each taking every so many items (cloudcore.gl.programs.dispatch)
void main()
{
#ifdef STARTS
    uint items = min(totals[total_at], room);
#else
    uint items = slots;
#endif
    for (uint i = gl_GlobalInvocationID.x; i < items; i += gl_NumWorkGroups.x * gl_WorkGroupSize.x)
        run(i, items);
}

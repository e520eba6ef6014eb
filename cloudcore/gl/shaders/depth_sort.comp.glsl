#version 430 core
// One pass of a stable least-significant-digit radix sort of (key, value)
// pairs of uint32, ascending by key, on DIGIT_BITS bits of the key from
// `shift` (reference: cloudcore.particles.depth_order.far_to_near, whose keys are
// the inverted bit patterns of float32 distances).  A pass is two stages,
// chosen by the stage defined, around a prefix sum (prefix_sum.comp.glsl):
//   COUNT    one workgroup a tile: how many of its keys have each digit,
//            digit-major so that, summed, all of digit 0 comes first, tile by
//            tile, and each count becomes where its (digit, tile) run starts;
//   SCATTER  one workgroup a tile: each key to its run's start plus the keys
//            of its digit before it in the tile.
// Stable because each invocation takes ITEMS consecutive keys in order and
// ranks them after those of every invocation before it in the tile, so equal
// keys keep their input order, pass after pass.  Four-bit digits keep the
// scatter's per-invocation counts (16) in registers and its prefix table
// (16 x 256 uints) in shared memory.

#define GROUP 256
#define DIGITS (1 << DIGIT_BITS)
#define TILE (GROUP * ITEMS)

layout(local_size_x = GROUP) in;

// past the prefix sum's bindings (0 and 1): its scan between the stages leaves these bound
layout(std430, binding = 2) readonly buffer KeysIn { uint keys_in[]; };
layout(std430, binding = 3) readonly buffer ValuesIn { uint values_in[]; };
layout(std430, binding = 4) writeonly buffer KeysOut { uint keys_out[]; };
layout(std430, binding = 5) writeonly buffer ValuesOut { uint values_out[]; };
// per (digit, tile), digit-major: COUNT writes the counts, the prefix sum turns them into output starts
layout(std430, binding = 6) buffer TileCounts { uint tile_counts[]; };
// where only the GPU knows how many pairs there are (a tile binning's): their count, at `count_at`
layout(std430, binding = 7) readonly buffer Counted { uint counted[]; };

uniform uint count;     // pairs to sort, or with `count_at` the most there can be (the buffers' room)
uniform uint count_at;  // where `counted` holds their count, or COUNT_GIVEN
uniform uint shift;     // the digit's lowest bit
uniform uint tiles;

const uint COUNT_GIVEN = 0xFFFFFFFFu;

uint pairs_to_sort()
{
    return count_at == COUNT_GIVEN ? count : min(count, counted[count_at]);
}

uint digit_of(uint key)
{
    return (key >> shift) & uint(DIGITS - 1);
}

#ifdef COUNT
shared uint histogram[DIGITS];

void main()
{
    uint tile = gl_WorkGroupID.x, thread = gl_LocalInvocationID.x, pairs = pairs_to_sort();
    if (tile * TILE >= pairs) {  // a tile of the room past the pairs (the whole group alike: before any barrier)
        if (thread < DIGITS)
            tile_counts[thread * tiles + tile] = 0u;
        return;
    }
    if (thread < DIGITS)
        histogram[thread] = 0u;
    barrier();
    uint first = tile * TILE + thread * ITEMS;
    for (uint i = 0u; i < ITEMS; ++i)
        if (first + i < pairs)
            atomicAdd(histogram[digit_of(keys_in[first + i])], 1u);
    barrier();
    if (thread < DIGITS)
        tile_counts[thread * tiles + tile] = histogram[thread];
}
#endif

#ifdef SCATTER
// per digit, per invocation: its keys of that digit, then (scanned) those of the invocations before it
shared uint prefix[DIGITS][GROUP];

void main()
{
    uint tile = gl_WorkGroupID.x, thread = gl_LocalInvocationID.x, pairs = pairs_to_sort();
    if (tile * TILE >= pairs)
        return;  // as COUNT's
    uint first = tile * TILE + thread * ITEMS;
    uint own[DIGITS];
    for (int d = 0; d < DIGITS; ++d)
        own[d] = 0u;
    for (uint i = 0u; i < ITEMS; ++i)
        if (first + i < pairs)
            own[digit_of(keys_in[first + i])] += 1u;
    for (int d = 0; d < DIGITS; ++d)
        prefix[d][thread] = own[d];
    barrier();
    for (uint offset = 1u; offset < GROUP; offset <<= 1) {
        uint before[DIGITS];
        for (int d = 0; d < DIGITS; ++d)
            before[d] = thread >= offset ? prefix[d][thread - offset] : 0u;
        barrier();
        for (int d = 0; d < DIGITS; ++d)
            prefix[d][thread] += before[d];
        barrier();
    }
    uint next[DIGITS];  // where this invocation's next key of each digit goes
    for (int d = 0; d < DIGITS; ++d)
        next[d] = tile_counts[uint(d) * tiles + tile] + prefix[d][thread] - own[d];
    for (uint i = 0u; i < ITEMS; ++i) {
        if (first + i >= pairs)
            break;
        uint key = keys_in[first + i];
        uint d = digit_of(key);
        keys_out[next[d]] = key;
        values_out[next[d]] = values_in[first + i];
        next[d] += 1u;
    }
}
#endif

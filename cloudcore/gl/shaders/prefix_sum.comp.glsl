#version 430 core
// Exclusive prefix sums of `count` uints, in place (reference: numpy's cumsum less each item), in three
// dispatches chosen by the stage defined, or one for a short array (SCAN alone):
//   BLOCK_SUMS  one workgroup a block of BLOCK items: their sum, into block_sums;
//   SCAN        one workgroup: `count` items of `values` scanned, each invocation a run of them in order
//               (over the blocks' sums, these become the blocks' starts);
//   BLOCKS      one workgroup a block: each item replaced by its block's start plus the items before it.
// Each invocation takes ITEMS consecutive items, so an invocation's memory reads are its own run and a
// block needs one scan across its invocations (Hillis-Steele, in shared memory).

#define GROUP 256
#define BLOCK (GROUP * ITEMS)

layout(local_size_x = GROUP) in;

layout(std430, binding = 0) buffer Values { uint values[]; };
layout(std430, binding = 1) buffer BlockSums { uint block_sums[]; };

uniform uint count;

shared uint sums[GROUP];

// sums[] scanned inclusively across the group, each invocation's `own` in its place first
void scan_group(uint thread, uint own)
{
    sums[thread] = own;
    barrier();
    for (uint offset = 1u; offset < GROUP; offset <<= 1) {
        uint before = thread >= offset ? sums[thread - offset] : 0u;
        barrier();
        sums[thread] += before;
        barrier();
    }
}

void main()
{
    uint thread = gl_LocalInvocationID.x;
#ifdef SCAN
    uint chunk = (count + GROUP - 1u) / GROUP;
    uint first = min(thread * chunk, count), last = min(first + chunk, count);
#else
    uint first = min(gl_WorkGroupID.x * BLOCK + thread * ITEMS, count), last = min(first + ITEMS, count);
#endif
    uint own = 0u;
    for (uint i = first; i < last; ++i)
        own += values[i];
    scan_group(thread, own);
#ifdef BLOCK_SUMS
    if (thread == GROUP - 1u)
        block_sums[gl_WorkGroupID.x] = sums[thread];
#else
#ifdef SCAN
    uint start = sums[thread] - own;
#else
    uint start = block_sums[gl_WorkGroupID.x] + sums[thread] - own;
#endif
    for (uint i = first; i < last; ++i) {
        uint item = values[i];
        values[i] = start;
        start += item;
    }
#endif
}

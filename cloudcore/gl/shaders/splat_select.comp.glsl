#version 430 core
// Chooses and keys one draw's particles on the GPU, one invocation per
// particle of its clouds: the work cloudcore.gl.splats.splat_batch does in
// numpy, so that the CPU's part of a draw does not grow with its particles.
// A particle is kept when it has any opacity (the near fade of splats, a
// transparent colour level, formation and blend weights) and lies in its
// cloud's depth range and in the frustum; its key is then its distance's
// far-to-near sort key (cloudcore.particles.depth_order.distance_keys), and the
// draw's indirect command counts it.  A particle left out gets the largest
// key, which no kept one has, so that after the sort (depth_sort.comp.glsl)
// the kept come first, far to near, in the count the command holds.
//
// The sort's values are the selection's slots; RESOLVE's ORDER stage then
// turns the sorted slots into particles, the draw's order.  A selection may
// feed many draws from one eye, each into its own cell of a layered target (a
// frame's impostor regenerations: cloudcore.gl.splats.SplatPass.draw_cells).
// Each cloud range names its cell, whose own command counts its particles;
// after the distance passes, RESOLVE's CELL_KEYS stage keys each sorted slot
// by its cell, and the sort's cell passes group the cells, each staying far
// to near (the sort is stable).  Cell c then holds the slots of its ranges,
// from those of the cells before it on, the kept first, as many as its
// command counts.
//
// Distances come from float32 centres relative to the eye, where the CPU
// computes them in float64: particles whose distances agree to a float32
// rounding may swap places, and one on a depth range's or the frustum's
// boundary may fall on the other side (tests/render/test_gpu_order.py bounds both).

layout(local_size_x = 64) in;

struct Range {
    uint start;    // the cloud's first particle
    uint before;   // the selection's particles in the clouds before it
    float near;    // its depth range: near < distance <= far
    float far;
    uint cell;     // the draw its particles go to: its command follows the first draw's
    uint unused[3];
};
layout(std430, binding = 3) readonly buffer Ranges { Range ranges[]; };
uniform uint count;        // the selection's particles, kept or not
uniform uint range_count;  // its clouds

// the range of slot i: the last starting at or before it
Range range_of(uint i)
{
    uint low = 0u, high = range_count - 1u;
    while (low < high) {
        uint middle = (low + high + 1u) / 2u;
        if (ranges[middle].before <= i)
            low = middle;
        else
            high = middle - 1u;
    }
    return ranges[low];
}

#ifdef RESOLVE
layout(std430, binding = 4) writeonly buffer Keys { uint keys[]; };
layout(std430, binding = 5) readonly buffer Values { uint values[]; };  // sorted slots
layout(std430, binding = 7) writeonly buffer Order { uint order[]; };

uniform bool cell_keys;  // CELL_KEYS: key each sorted slot by its cell; else ORDER: its particle into the order
uniform uint first;      // ORDER: the order's slot of the selection's first

void resolve(uint j)
{
    Range range = range_of(values[j]);
    if (cell_keys)
        keys[j] = range.cell;
    else
        order[first + j] = range.start + (values[j] - range.before);
}

void main()
{
    for (uint j = gl_GlobalInvocationID.x; j < count; j += gl_NumWorkGroups.x * gl_WorkGroupSize.x)
        resolve(j);
}
#else
// splat_shade.comp.glsl's Particle records, PARTICLE_FLOATS floats each: only the centre and radius are read
layout(std430, binding = 0) readonly buffer Particles { float particles[]; };
layout(std430, binding = 1) readonly buffer Formation { float formation[]; };
// per particle: bit 0 faded next to the eye (splats; sprites lock instead), bit 1 opaque at all
layout(std430, binding = 2) readonly buffer Flags { uint flags[]; };
layout(std430, binding = 4) writeonly buffer Keys { uint keys[]; };
layout(std430, binding = 5) writeonly buffer Values { uint values[]; };
// DrawElementsIndirectCommands, one a cell: their count, six indices a particle kept, is counted here
layout(std430, binding = 6) buffer Command { uint command[]; };

uniform uint command_at;   // the first cell's command's first uint in the buffer
uniform vec3 eye;
uniform vec4 planes[6];    // the frustum, relative to the eye, inside positive
uniform bool cull_to_frustum;

const uint LEFT_OUT = 0xFFFFFFFFu;

void select(uint i)
{
    Range range = range_of(i);
    uint index = range.start + (i - range.before);
    uint record = index * uint(PARTICLE_FLOATS);
    vec4 centre_radius = vec4(particles[record], particles[record + 1u], particles[record + 2u], particles[record + 3u]);
    vec3 offset = centre_radius.xyz - eye;
    float distance = length(offset);
    uint flag = flags[index];
    bool kept = (flag & 2u) != 0u && formation[index] > 0.0
             && (distance > FADE_START_RADII * centre_radius.w || (flag & 1u) == 0u)
             && distance > range.near && distance <= range.far;
    if (cull_to_frustum)
        for (int p = 0; p < 6; ++p)
            kept = kept && dot(planes[p].xyz, offset) + planes[p].w >= -SPLAT_REACH * centre_radius.w;
    values[i] = i;
    if (kept) {
        keys[i] = min(~floatBitsToUint(distance), LEFT_OUT - 1u);
        atomicAdd(command[command_at + uint(COMMAND_UINTS) * range.cell], 6u);
    } else {
        keys[i] = LEFT_OUT;
    }
}

// as many invocations as the GL dispatches, each taking every so many slots (cloudcore.gl.programs.dispatch)
void main()
{
    for (uint i = gl_GlobalInvocationID.x; i < count; i += gl_NumWorkGroups.x * gl_WorkGroupSize.x)
        select(i);
}
#endif

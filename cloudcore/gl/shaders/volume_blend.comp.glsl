#version 430 core
// Yusov's volume-aware blending (HPG 2014, section 5.5, eq. 10-17) without pixel-shader ordering,
// or with PLAIN defined the billboards' own blending done the same way (a compute compositor of plain
// splats, for GPUs whose raster is a small part of the chip: cloudcore.gl.tile_binning):
// one work group per screen tile, one invocation per pixel, each walking its tile's particles in the
// batch's far-to-near order (cloudcore.gl.tile_binning; PLAIN: near to far, below) and
// compositing their segments along its ray as the numpy reference does (cloudcore.light.volume_blending.volume_blend):
// one segment held (extent, optical depth, colour), the farther of two apart into the frame, or of
// two overlapping the back part and the intersection, the front part held.  A pixel is one invocation's alone,
// so its read-modify-write of the target needs no interlock.  Each pixel reads its tile's splats
// itself: gathering them into shared memory once per group (as 3D Gaussian splatting rasterisers
// do on GPUs) was no faster on llvmpipe, whose barriers are costly (docs/shading.md).
//
// A particle's segment along the ray: the ray meets the splat's plane at d radii from its centre
// (as splat.frag.glsl measures it); opacity alpha K(d) gives the optical depth -ln(1 - alpha K(d)),
// spread over the chord of half length r sqrt(1 - d^2) around the ray's closest approach; the world's
// depth cuts the chord.  Each splat is read as tile_bin.comp.glsl made it of the instance splat_shade.comp.glsl
// built: its image in pixels, colour, centre and radius (a third of the instance's bytes).  A splat faces the
// image plane, so its quad's image is a rectangle over which the raster interpolates the kernel's coordinates
// linearly: d is the pixel's offset from the image's centre over its half sizes, with no ray to intersect
// with the splat's plane (the plain walk took 108 against 200 ms on llvmpipe, docs/journal.md, "The compute
// passes cut to a quarter again").

layout(local_size_x = TILE_PIXELS, local_size_y = TILE_PIXELS) in;

layout(std430, binding = 6) readonly buffer TileStarts { uint tile_starts[]; };
layout(std430, binding = 7) readonly buffer TileEntries { uint tile_entries[]; };
#include "binned_splats.glsl"  // the occupied tiles, one group each, and the splats as binned
layout(rgba16f, binding = 0) uniform image2D target;  // premultiplied linear colour, what was drawn so far
uniform sampler2D world_depth;  // the frame's depth, window coordinates in [0, 1]

uniform ivec2 size;
uniform int tiles_across;
uniform vec3 view_right;
uniform vec3 view_up;
uniform vec3 view_forward;
uniform vec2 focal;        // projection[0][0], projection[1][1]
uniform vec2 depth_terms;  // projection[2][2], projection[2][3]: window depth back to eye depth

const float TINY = 1e-30;
const float FAR = 3.0e38;  // no world along the ray

struct Segment {
    float near;
    float far;
    float depth;  // optical
    vec3 colour;  // not premultiplied
};

void over(inout vec4 image, vec3 premultiplied, float transmittance)
{
    image.rgb = premultiplied + transmittance * image.rgb;
    image.a = (1.0 - transmittance) + transmittance * image.a;
}

void over_whole(inout vec4 image, Segment s)
{
    float transmittance = exp(-s.depth);
    over(image, s.colour * (1.0 - transmittance), transmittance);
}

float kernel(float d2)
{
    float floor_value = exp(-SPLAT_SHARPNESS);
    return max((exp(-SPLAT_SHARPNESS * d2) - floor_value) / (1.0 - floor_value), 0.0);
}

// the particle's segment along `ray` through `pixel`, cut at `opaque`; depth 0 where the ray misses it
Segment segment_of(Disc p, vec2 pixel, vec3 ray, float opaque)
{
    Segment s = Segment(0.0, 0.0, 0.0, vec3(0.0));
    float alpha = p.colour.a;
    float d2 = d2_at(p, pixel);
    if (alpha <= 0.0 || d2 >= 1.0)
        return s;
    float opacity = min(alpha * kernel(d2), 1.0);
    float depth = opacity < 1.0 ? min(-log(1.0 - opacity), MAX_OPTICAL_DEPTH) : MAX_OPTICAL_DEPTH;
    float half_length = sqrt(p.centre_r2.w * max(1.0 - d2, 0.0));
    float closest = dot(ray, p.centre_r2.xyz);
    s.near = closest - half_length;
    float whole_far = closest + half_length;
    s.far = clamp(opaque, s.near, whole_far);
    s.depth = half_length > 0.0 ? depth * (s.far - s.near) / max(whole_far - s.near, TINY) : 0.0;
    s.colour = p.colour.rgb / alpha;
    return s;
}

void composite(uint tile)
{
    ivec2 pixel = TILE_PIXELS * ivec2(tile % uint(tiles_across), tile / uint(tiles_across))
                + ivec2(gl_LocalInvocationID.xy);
    if (any(greaterThanEqual(pixel, size)))
        return;
    float stored = texelFetch(world_depth, pixel, 0).r;
    float world = stored >= 1.0 ? FAR : depth_terms.y / ((2.0 * stored - 1.0) + depth_terms.x);  // eye depth
    vec4 image = imageLoad(target, pixel);

#ifdef PLAIN
    // billboards blended as splat.frag.glsl's fragments are (premultiplied, GL_ONE, GL_ONE_MINUS_SRC_ALPHA),
    // where the ray meets the quad in front of the world (the raster's depth test).  The raster blends far to
    // near, each splat over the pixel; the same sum taken near to far (each splat under those in front of it)
    // is the same picture, and it can stop once the pixel lets through too little to show: the splats left
    // would change it by at most the transmittance times their brightest radiance, since what was drawn
    // before stays behind them, weighed by the transmittance, as the splats would have left it where opaque.
    // The pixel stays float32 through its splats, where the raster rounds it to half floats at each blend.
    vec4 in_front = vec4(0.0);  // premultiplied: the splats nearer than the next one
    float transmittance = 1.0;
    for (uint k = tile_starts[tile + 1u]; k > tile_starts[tile] && transmittance > FINISHED_TRANSMITTANCE;) {
        Disc p = discs[tile_entries[--k]];
        float d2 = d2_at(p, vec2(pixel));
        if (d2 >= 1.0 || dot(p.centre_r2.xyz, view_forward) >= world)
            continue;
        vec4 source = p.colour * kernel(d2);
        in_front += transmittance * source;
        transmittance *= 1.0 - source.a;
    }
    image = in_front + transmittance * image;
#else
    vec2 ndc = (vec2(pixel) + 0.5) / vec2(size) * 2.0 - 1.0;
    vec3 ray = normalize(ndc.x / focal.x * view_right + ndc.y / focal.y * view_up + view_forward);
    float opaque = stored >= 1.0 ? FAR : world / dot(ray, view_forward);  // the world's distance along the ray
    Segment held = Segment(0.0, 0.0, 0.0, vec3(0.0));
    for (uint k = tile_starts[tile]; k < tile_starts[tile + 1u]; ++k) {
        Segment s = segment_of(discs[tile_entries[k]], vec2(pixel), ray, opaque);
        if (s.depth <= 0.0)
            continue;
        if (held.depth <= 0.0) {
            held = s;
            continue;
        }
        if (s.near >= held.far || s.far <= held.near) {  // apart: the farther goes into the frame
            if (s.near < held.near) {
                over_whole(image, held);
                held = s;
            } else {
                over_whole(image, s);
            }
            continue;
        }
        // overlapping (eq. 10-17): the back part, then the intersection, into the frame; the front held
        float density0 = held.depth / max(held.far - held.near, TINY);
        float density1 = s.depth / max(s.far - s.near, TINY);
        float front_start = min(held.near, s.near), front_end = max(held.near, s.near);
        float back_start = min(held.far, s.far), back_end = max(held.far, s.far);
        bool held_first = held.near <= s.near, held_last = held.far >= s.far;
        float back_t = exp(-(held_last ? density0 : density1) * (back_end - back_start));  // eq. 12
        over(image, (held_last ? held.colour : s.colour) * (1.0 - back_t), back_t);  // eq. 13, 16-17
        float inside_t = exp(-(density0 + density1) * max(back_start - front_end, 0.0));  // eq. 14
        float weight0 = density0 / max(density0 + density1, TINY);
        over(image, mix(s.colour, held.colour, weight0) * (1.0 - inside_t), inside_t);  // eq. 15, 16-17
        float front_depth = (held_first ? density0 : density1) * (front_end - front_start);  // eq. 10
        held = Segment(front_start, front_end, front_depth, held_first ? held.colour : s.colour);
    }
    if (held.depth > 0.0)
        over_whole(image, held);
#endif
    imageStore(target, pixel, image);
}

// as many groups as the binning dispatches, each taking every so many occupied tiles: llvmpipe pays for a
// group of the volume variant even where it has nothing to do (the default view's 2,644 empty tiles of 4,800
// at 640x480 cost 160 ms when every tile was dispatched)
void main()
{
    for (uint group = gl_WorkGroupID.x; group < occupied_count; group += gl_NumWorkGroups.x)
        composite(occupied[group]);
}

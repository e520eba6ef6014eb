#version 430 core
// Builds batches of particles for their eyes, one invocation per particle:
// the quad's four corners and their premultiplied colours, in the batch's
// far-to-near order, for splat.vert.glsl to draw.  Once per particle here
// rather than at each corner in the vertex shader: on a software rasteriser
// vertex work is the cost.
//
// Colour, Harris (reference cloudcore.particles.buffer.ParticleShading.seen_from):
// per light, the incident light of the light pass times the phase function at
// the angle between the view ray and the light, times the scattering
// coefficient, plus ambient; for Yusov's eye pass (reference
// cloudcore.light.precomputed.EyePassProfiles.at) the phase function times the
// reference particle's single scattering plus its multiple scattering, both
// read from the particle's profile row linearly in mu, stand in for the
// phase function.  The part of a particle's light that a cloud's lit face sent
// back (RETURNED) arrives from every direction: the phase function's mean, 1,
// stands in for the phase function there.  Colour, Wang's artist model (reference
// cloudcore.artist.artist_shading.artist_colours): the cloud's five vertical colour
// levels at each corner's height plus the directional term of its shading
// group, per corner.  Opacity: splats fade out next to the eye; sprites lock
// their facing there (cloudcore.artist.facing) and fade by its angle; forming
// clouds scale both (cloudcore.artist.formation).
//
// Orientation (cloudcore.artist.particle_styles): splats lie in the image plane;
// sprites face the eye (or their locked facing) with world up projected
// into their plane (cloudcore.artist.facing.sprite_axes), or lie flat; both turned
// by their rotation.  Corners are written relative to the eye, so float32
// keeps tiny particles far from the origin their size.
//
// Variants: FACING (sprites not in the image plane), ARTIST (Wang's colours),
// PROFILES (Yusov's eye pass), RETURNED (the lit face's light), PIXEL_TERMS (what
// splat.frag.glsl shades a splat by per pixel: cloudcore.light.splat_look) and AIR (aerial perspective by the particle's
// distance from the eye, for the cloud pass's batches, never an impostor's,
// whose texture is seen from elsewhere; with LIGHT_SHAFTS, less the shafts' share of it) compile their code in only for batches that
// have them: llvmpipe paid for the code behind the branches, so a batch of Harris's
// splats paid for the artist colours of every corner.
//
// One dispatch shades a run of batches (a frame's impostor regenerations, the
// cloud pass's draws), each with its own eye and image plane: an invocation
// finds its slot's batch in the table, by binary search.  A dispatch a batch
// cost 0.16 ms of binding and uniforms on the CPU each, however few its particles.

layout(local_size_x = 64) in;

struct Particle {
    vec4 centre_radius;       // world xyz, radius
    vec4 scattering_opacity;  // scattering coefficient x tint (rgb), opacity
    vec4 ambient;             // ambient x opacity x tint (rgb), the optical depth the sun's light falls by inside it
    vec4 group_cloud;         // shading group centre xyz, cloud index
    vec4 sprite;              // atlas cell (-1: Gaussian splat), rotation (radians), profile row (-1: none), unused
    float incident[MAX_LIGHTS];
};
struct CloudStyle {
    vec4 level_colours[5];       // RGBA, RGB times the hour's percentage
    vec4 level_heights;          // the first four level heights (fractions of the cloud's height)
    vec4 last_height_extent;     // fifth level height, lowest and highest particle centre y, artist (0 or 1)
    vec4 directional_colour;     // rgb, facing (FACING_* of cloudcore.artist.particle_styles)
    vec4 directional_range;      // min, median, max, unused
    vec4 sun;                    // toward the sun, unused
};
struct Instance {
    vec4 corners[4];  // relative to the eye; w: atlas cell (-1: Gaussian splat)
    vec4 colours[4];  // premultiplied linear rgb, opacity
};
layout(std430, binding = 0) readonly buffer Particles { Particle particles[]; };
layout(std430, binding = 1) readonly buffer Formation { float formation[]; };
layout(std430, binding = 2) readonly buffer Order { uint order[]; };
layout(std430, binding = 3) writeonly buffer Instances { Instance instances[]; };
layout(std430, binding = 4) readonly buffer Clouds { CloudStyle clouds[]; };
layout(std430, binding = 5) readonly buffer Facing { vec4 facing[]; };  // locked normal, fade (< 0: unlocked)
// rows of Yusov's eye pass: single then multiple scattering at profile_samples mu from -1 to 1
layout(std430, binding = 6) readonly buffer Profiles { float profiles[]; };

struct Batch {
    uvec4 slots;     // first slot in the order and instance buffers, particles; unused
    vec4 eye;
    vec4 view_right;  // the image plane's axes in the world, for splats
    vec4 view_up;
};
layout(std430, binding = 7) readonly buffer Batches { Batch batches[]; };
#ifdef RETURNED
// per particle and light (light_count a particle): the part of its incident light a lit face sent back
layout(std430, binding = 8) readonly buffer Returned { float returned[]; };
#endif
#ifdef PIXEL_TERMS
// per slot, beside its instance: what the raster shades a splat by per pixel (cloudcore.light.splat_look)
struct PixelTerms {
    vec4 sun;    // the part of the colours (rgb, premultiplied) that is the sun's (the first light's) light
                 // scattered at the phase's angle; w: the optical depth across the particle by which that
                 // light falls inside it (cloudcore.light.splat_look.inner_light_depth)
    vec4 light;  // toward the sun; w: the particle's index, its detail noise's offset
};
layout(std430, binding = 9) writeonly buffer Terms { PixelTerms terms[]; };
#endif

uniform uint first;  // the dispatch's first slot, that of its first batch
uniform uint slot_count;  // the slots it covers: its batches' and the alignment gaps between them
uniform uint batch_count;
uniform int light_count;
uniform vec3 light_direction[MAX_LIGHTS];  // toward the light
uniform vec3 light_radiance[MAX_LIGHTS];
uniform int phase_kind;  // cloudcore.light.phase.PHASE_NAMES order
uniform float g;
uniform int profile_samples;
#ifdef AIR
#include "aerial_perspective.glsl"
#endif
#ifdef LIGHT_SHAFTS
#include "light_shafts_read.glsl"
uniform mat4 shaft_view_projection;  // the frame's, of points relative to its eye (the batch's)
#endif

const int FACING_SPLAT = 0;
const int FACING_HORIZONTAL = 2;
const vec2 CORNERS[4] = vec2[](vec2(-1.0, -1.0), vec2(1.0, -1.0), vec2(-1.0, 1.0), vec2(1.0, 1.0));

float phase(float mu)
{
    mu = clamp(mu, -1.0, 1.0);
    float rayleigh = 0.75 * (1.0 + mu * mu);
    if (phase_kind == 0)
        return rayleigh;
    float lobe = (1.0 - g * g) / pow(1.0 + g * g - 2.0 * g * mu, 1.5);
    return phase_kind == 1 ? lobe : 2.0 * rayleigh / (2.0 + g * g) * lobe;
}

// cloudcore.maths.ramps.smoothstep; GLSL's own is undefined for a zero-width ramp
float ramp(float edge0, float edge1, float x)
{
    float t = clamp((x - edge0) / max(edge1 - edge0, 1e-30), 0.0, 1.0);
    return t * t * (3.0 - 2.0 * t);
}

// the row's profile `part` (0 single, 1 multiple) at mu, linear between samples
float profile(int row, int part, float mu)
{
    float position = (clamp(mu, -1.0, 1.0) + 1.0) * 0.5 * float(profile_samples - 1);
    int below = min(int(position), profile_samples - 2);
    int start = (row * 2 + part) * profile_samples + below;
    return mix(profiles[start], profiles[start + 1], position - float(below));
}

// the particle's colour and opacity; `sun`: the part of the colour the first light scattered at the phase's
// angle (the rest has no direction inside the particle)
vec4 harris_colour(Particle p, uint index, vec3 view_ray, out vec3 sun)
{
    int row = int(p.sprite.z);
    vec3 scattered = vec3(0.0);
    sun = vec3(0.0);
    for (int light = 0; light < light_count; ++light) {
        float mu = dot(view_ray, light_direction[light]);
        float factor = phase(mu);
        float around = 1.0;  // the phase function's mean, for the light sent back from every direction
#ifdef PROFILES
        if (row >= 0) {
            float single = profile(row, 0, mu), multiple = profile(row, 1, mu);
            factor = factor * single + multiple;
            around = single + multiple;
        }
#endif
#ifdef RETURNED
        float back = returned[index * uint(light_count) + uint(light)];
        vec3 direct = (p.incident[light] - back) * factor * light_radiance[light];
        scattered += direct + back * around * light_radiance[light];
#else
        vec3 direct = p.incident[light] * factor * light_radiance[light];
        scattered += direct;
#endif
        if (light == 0)
            sun = direct * p.scattering_opacity.rgb;
    }
    return vec4(scattered * p.scattering_opacity.rgb + p.ambient.rgb, p.scattering_opacity.a);
}

#ifdef ARTIST
// cloudcore.artist.artist_shading.artist_colours at one vertex, premultiplied
vec4 artist_colour(CloudStyle style, vec3 vertex, vec3 group_centre)
{
    float bottom = style.last_height_extent.y, top = style.last_height_extent.z;
    float f = top > bottom ? clamp((vertex.y - bottom) / (top - bottom), 0.0, 1.0) : 0.5;
    float heights[5] = float[](style.level_heights.x, style.level_heights.y, style.level_heights.z,
                               style.level_heights.w, style.last_height_extent.x);
    vec4 ambient = style.level_colours[0];
    for (int level = 1; level < 5; ++level)
        if (f > heights[level - 1])
            ambient = mix(style.level_colours[level - 1], style.level_colours[level],
                          clamp((f - heights[level - 1]) / (heights[level] - heights[level - 1]), 0.0, 1.0));
    vec3 v = vertex - group_centre;
    float d = length(v) > 0.0 ? dot(v / length(v), style.sun.xyz) : 0.0;
    vec3 range = style.directional_range.xyz;
    float t = d < 0.0 ? range.y + d * (range.y - range.x) : range.y + d * (range.z - range.y);
    vec4 colour = clamp(ambient + vec4(style.directional_colour.rgb * t, 0.0), 0.0, 1.0);
    return vec4(colour.rgb * colour.a, colour.a);
}
#endif

void shade(uint invocation)
{
    uint slot = first + invocation;
    uint low = 0u, high = batch_count - 1u;  // the last batch starting at or before the slot
    while (low < high) {
        uint middle = (low + high + 1u) / 2u;
        if (batches[middle].slots.x <= slot)
            low = middle;
        else
            high = middle - 1u;
    }
    Batch batch = batches[low];
    if (slot >= batch.slots.x + batch.slots.y)
        return;  // between two batches
    vec3 eye = batch.eye.xyz, view_right = batch.view_right.xyz, view_up = batch.view_up.xyz;
    uint index = order[slot];
    Particle p = particles[index];
    CloudStyle style = clouds[int(p.group_cloud.w)];
    int facing_kind = int(style.directional_colour.w);
    vec3 offset = p.centre_radius.xyz - eye;
    float distance = length(offset);
    vec3 view_ray = offset / max(distance, 1e-30);
    float radius = p.centre_radius.w;

    vec3 right = view_right, up = view_up;
    float fade = ramp(FADE_START_RADII * radius, FADE_END_RADII * radius, distance);
#ifdef FACING
    if (facing_kind != FACING_SPLAT) {
        vec4 lock = facing[index];
        vec3 normal = facing_kind == FACING_HORIZONTAL ? vec3(0.0, 1.0, 0.0)
                    : lock.w >= 0.0 ? lock.xyz : (distance > 0.0 ? -view_ray : vec3(0.0, 0.0, 1.0));
        fade = facing_kind == FACING_HORIZONTAL || lock.w < 0.0 ? 1.0 : lock.w;
        vec3 reference = length(normal.xz) < 1e-6 ? vec3(0.0, 0.0, -1.0) : vec3(0.0, 1.0, 0.0);
        vec3 axis = normalize(cross(reference, normal));
        up = cross(normal, axis);
        float c = cos(p.sprite.y), s = sin(p.sprite.y);
        right = c * axis + s * up;
        up = cross(normal, right);
    }
#endif
    fade *= formation[index];

    vec3 sun;
#ifdef ARTIST
    bool artist = style.last_height_extent.w > 0.5;
    vec4 colour = artist ? vec4(0.0) : harris_colour(p, index, view_ray, sun) * fade;
    sun = artist ? vec3(0.0) : sun;  // Wang's colours are the artist's: no light inside the particle
#else
    vec4 colour = harris_colour(p, index, view_ray, sun) * fade;
#endif
    sun *= fade;
#ifdef AIR
    // the air in front of the particle, by its centre, added where it covers what is behind
    // (cloudcore.light.air_between): read once for its four corners
    vec3 air_transmittance, air_in_scattered;
    air_toward(offset, air_transmittance, air_in_scattered);
#ifdef LIGHT_SHAFTS
    // Yusov's cut: less the share of that air the clouds' shadows keep from the eye, marched up to the clouds'
    // nearest distance where the particle's centre falls on the screen, as the terrain's and the impostors' air
    vec4 clip = shaft_view_projection * vec4(offset, 1.0);
    if (clip.w > 0.0)
        air_in_scattered *= 1.0 - light_shafts_at(clamp(clip.xy / clip.w, -1.0, 1.0)).a;
#endif
    sun *= air_transmittance;
#endif
#ifdef PIXEL_TERMS
    terms[slot].sun = vec4(sun, p.ambient.w);
    terms[slot].light = vec4(light_count > 0 ? light_direction[0] : vec3(0.0, 1.0, 0.0), float(index));
#endif
    for (int k = 0; k < 4; ++k) {
        vec3 corner = offset + radius * (CORNERS[k].x * right + CORNERS[k].y * up);
        instances[slot].corners[k] = vec4(corner, p.sprite.x);
#ifdef ARTIST
        vec4 seen = artist ? artist_colour(style, corner + eye, p.group_cloud.xyz) * fade : colour;
#else
        vec4 seen = colour;
#endif
#ifdef AIR
        seen.rgb = seen.rgb * air_transmittance + seen.a * air_in_scattered;
#endif
        instances[slot].colours[k] = seen;
    }
}

// as many invocations as the GL dispatches, each taking every so many slots (cloudcore.gl.programs.dispatch)
void main()
{
    for (uint i = gl_GlobalInvocationID.x; i < slot_count; i += gl_NumWorkGroups.x * gl_WorkGroupSize.x)
        shade(i);
}

#version 420 core
// Light shafts, marched at a fraction of the screen's resolution before the world is drawn: the air's light that
// the clouds' shadow keeps from the eye along each pixel's ray, up to the terrain (its depth drawn at this
// resolution) or the air volume's reach, and its share of the light of all the air there (by luminance), for the
// sky and the terrain to take off theirs (light_shafts_read.glsl).  cloudcore/light/light_shafts.py's shadowed_in_scattering, its steps'
// transmittance read at an offset dithered across pixels (interleaved gradient noise, Jimenez 2014): a fixed
// offset bands the shafts into the steps' stripes.

#include "aerial_perspective.glsl"
#include "cloud_shadow.glsl"
#include "planet_ground.glsl"

layout(binding = 0) uniform sampler2D terrain_depth;  // this target's size
uniform vec3 eye_position;
uniform vec3 view_right;
uniform vec3 view_up;
uniform vec3 view_forward;
uniform vec2 focal;        // the projection's [0][0] and [1][1]
uniform vec2 depth_terms;  // the projection's [2][2] and [2][3]
uniform int steps;         // cloudcore.light.light_shafts.SHAFT_STEPS
uniform float sky_lowest_up;  // the sky draws a ray below this cosine to the up as the one at it (sky.frag.glsl)
// with the far ground (sky.frag.glsl's FAR_GROUND): (the eye's altitude over the planet's ground, the planet's
// radius), metres, and a ray below the horizon past the terrain ends on the ground; x < 0: none
uniform vec2 planet_ground;

out vec4 shadowed_and_share;

// light_shafts.py's shaft_segments: [start, end] of the ray inside the map's prism (u and v within [0, 1], the
// slice coordinate at least 0), end <= start where it misses it; the ray from the map's `at` by `rate` a metre
vec2 shaft_segment(vec3 at, vec3 rate, float distance)
{
    vec2 segment = vec2(0.0, distance);
    const vec3 low = vec3(0.0);
    const vec3 high = vec3(1.0, 1.0, 3.0e38);
    for (int axis = 0; axis < 3; ++axis) {
        if (abs(rate[axis]) > 1e-15) {
            float a = (low[axis] - at[axis]) / rate[axis];
            float b = (high[axis] - at[axis]) / rate[axis];
            segment = vec2(max(segment.x, min(a, b)), min(segment.y, max(a, b)));
        } else if (at[axis] < low[axis] || at[axis] > high[axis]) {
            segment.y = -1.0;
        }
    }
    return segment;
}

void main()
{
    ivec2 pixel = ivec2(gl_FragCoord.xy);
    vec2 across = ((vec2(pixel) + 0.5) / vec2(textureSize(terrain_depth, 0)) * 2.0 - 1.0) / focal;
    vec3 direction = normalize(across.x * view_right + across.y * view_up + view_forward);
    float depth = texelFetch(terrain_depth, pixel, 0).r;
    float view_depth = depth_terms.y / (2.0 * depth - 1.0 + depth_terms.x);  // along the view's forward
    float distance = depth >= 1.0 ? air_max_distance : min(view_depth * length(vec3(across, 1.0)), air_max_distance);
    if (depth >= 1.0 && planet_ground.x >= 0.0)
        distance = min(distance, distance_to_ground(planet_ground.x, planet_ground.y, direction.y));
    else if (depth >= 1.0 && direction.y < sky_lowest_up) {
        // past the terrain's edge (of a sky without the far ground) the sky draws the air at the horizon: its
        // shafts too, not those of air under the ground
        vec2 level = normalize(direction.xz + vec2(1e-12, 0.0)) * sqrt(1.0 - sky_lowest_up * sky_lowest_up);
        direction = vec3(level.x, sky_lowest_up, level.y);
    }
    vec3 shadowed = vec3(0.0);
    vec2 uv = air_direction_uv(direction);
    vec3 whole = textureLod(air_in_scattered, vec3(uv, air_distance_w(distance)), 0.0).rgb;
    // the ray in the map: affine in the distance along it
    vec3 map_at = (world_to_cloud_shadow * vec4(eye_position, 1.0)).xyz;
    vec3 map_rate = mat3(world_to_cloud_shadow) * direction;
    vec2 segment = shaft_segment(map_at, map_rate, distance);
    if (cloud_shadows && segment.y > segment.x) {
        float offset = fract(52.9829189 * fract(dot(gl_FragCoord.xy, vec2(0.06711056, 0.00583715))));
        float step_m = (segment.y - segment.x) / float(steps);
        // along the ray only the volume's distance coordinate changes
        vec3 before = textureLod(air_in_scattered, vec3(uv, air_distance_w(segment.x)), 0.0).rgb;
        for (int step = 0; step < steps; ++step) {
            float w = air_distance_w(segment.x + step_m * float(step + 1));
            vec3 after = textureLod(air_in_scattered, vec3(uv, w), 0.0).rgb;
            vec3 inside = map_at + map_rate * (segment.x + step_m * (float(step) + offset));
            shadowed += (1.0 - cloud_shadow_transmittance_mapped(inside)) * max(after - before, vec3(0.0));
            before = after;
        }
    }
    const vec3 LUMINANCE = vec3(0.2126, 0.7152, 0.0722);  // Rec. 709
    float share = clamp(dot(shadowed, LUMINANCE) / max(dot(whole, LUMINANCE), 1e-12), 0.0, 1.0);
    shadowed_and_share = vec4(shadowed, share);
}

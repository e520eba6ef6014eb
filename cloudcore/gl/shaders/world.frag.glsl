#version 420 core
// The world in linear RGB: pyrender's terrain over the sky, the atmosphere's or a vertical gradient; under the
// atmosphere the terrain is seen through the air between it and the eye.
//
// pyrender drew sRGB-encoded vertex colours (8 bits are too coarse for linear
// colour in the shadows) over a transparent black background, and multisample
// resolve averaged them with it: a pixel holds (coverage * colour, coverage).
// The sky reads its tables as cloudcore/light/sky_background.py does.

layout(binding = 0) uniform sampler2D world_texture;
uniform mat4 inverse_view_projection;
uniform bool physical_sky;
// the gradient
uniform vec3 zenith_colour;
uniform vec3 horizon_colour;
// the atmosphere: its sky-view table (cloudcore/atmosphere/sky_view.py) seen from the scene's origin
layout(binding = 1) uniform sampler2D sky_view_table;
uniform vec2 sky_view_size;          // its (width, height): 192 x 108, 96 x 54 for a preview
uniform float zenith_horizon_angle;  // pi less the horizon's angle below the horizontal
uniform float horizon_cosine;        // the cosine to the up of the ray grazing the ground
uniform vec3 sun_direction;
uniform vec3 sun_disc_scale;         // the disc's colour per unit of its normalised radiance
uniform float pixel_angle;           // radians a pixel spans: the disc's rim is spread over it
// aerial perspective on the terrain (the physical sky alone): its depth, copied after pyrender drew it
uniform bool through_air;
layout(binding = 2) uniform sampler2D world_depth;
uniform vec3 eye_position;
#include "aerial_perspective.glsl"
// the sun's part of the terrain's light, apart from the vertex colours' where the clouds shadow it: per heightfield
// vertex, vertex (i, j) at terrain_sun_origin + (i, j) terrain_sun_spacing (x, z), scaled by the clouds' map
uniform bool sun_apart;
layout(binding = 7) uniform sampler2D terrain_sun;
uniform vec2 terrain_sun_origin;
uniform vec2 terrain_sun_spacing;
#include "cloud_shadow.glsl"

const float SUN_ANGULAR_RADIUS = 0.004651302;  // radians(0.533 / 2), cloudcore/atmosphere/sun_disc.py
const float LIMB_DARKENING = 0.6;
const float PI = 3.14159265358979;

in vec2 ndc;
out vec4 frag_colour;

vec3 srgb_decode(vec3 encoded)
{
    vec3 low = encoded / 12.92;
    vec3 high = pow((encoded + 0.055) / 1.055, vec3(2.4));
    return mix(high, low, lessThanEqual(encoded, vec3(0.04045)));
}

vec3 unproject(float depth)
{
    vec4 world = inverse_view_projection * vec4(ndc, depth, 1.0);
    return world.xyz / world.w;
}

vec3 gradient_sky(vec3 ray)
{
    // horizon colour at and below the horizon line; the square root keeps the
    // pale band near the horizon narrow, as in a clear sky
    return mix(horizon_colour, zenith_colour, sqrt(clamp(ray.y, 0.0, 1.0)));
}

vec2 sky_view_uv(vec3 ray)
{
    // sky_view.py's sky_view_uv over the horizon (the ground's half of the table is not drawn, `sky`): the zenith
    // angle squared toward the horizon, the azimuth toward the sun
    float zenith_angle = acos(clamp(ray.y, -1.0, 1.0));
    float v = 0.5 * (1.0 - sqrt(clamp(1.0 - zenith_angle / zenith_horizon_angle, 0.0, 1.0)));
    float lengths = length(ray.xz) * length(sun_direction.xz);
    float light_view_cosine = lengths > 1e-12 ? clamp(dot(ray.xz, sun_direction.xz) / lengths, -1.0, 1.0) : 1.0;
    float u = sqrt(clamp(0.5 - 0.5 * light_view_cosine, 0.0, 1.0));
    // table_sampling.py's unit_to_sub_uv
    return (vec2(u, v) + 0.5 / sky_view_size) * (sky_view_size / (sky_view_size + 1.0));
}

vec3 sun_disc(vec3 ray)
{
    // sun_disc.py's disc_radiance: the angle by its chord (acos loses it near 0 in float32); nearly every
    // pixel is farther than the disc's rim and skips it
    float chord = length(ray - sun_direction);
    if (chord > 2.0 * sin(0.5 * (SUN_ANGULAR_RADIUS + pixel_angle)))
        return vec3(0.0);
    float angle = 2.0 * asin(clamp(0.5 * chord, 0.0, 1.0));
    float radius_share = min(angle / SUN_ANGULAR_RADIUS, 1.0);
    float limb = 1.0 - LIMB_DARKENING * (1.0 - sqrt(1.0 - radius_share * radius_share));
    float solid_angle = 2.0 * PI * (1.0 - cos(SUN_ANGULAR_RADIUS));
    float coverage = clamp((SUN_ANGULAR_RADIUS - angle) / max(pixel_angle, 1e-9) + 0.5, 0.0, 1.0);
    return coverage * limb / ((1.0 - LIMB_DARKENING / 3.0) * solid_angle) * sun_disc_scale;
}

vec3 sky(vec3 ray)
{
    if (!physical_sky)
        return gradient_sky(ray);
    // below the horizon the terrain stands for the ground: past the world's edge the air at the horizon is
    // drawn, as sky_background.py's over_the_horizon does (HORIZON_MARGIN), not the table's grey ground
    float up = horizon_cosine + 1e-3;
    if (ray.y < up) {
        float across = length(ray.xz);
        vec2 level = across > 1e-12 ? ray.xz * (sqrt(1.0 - up * up) / across) : vec2(sqrt(1.0 - up * up), 0.0);
        vec3 air = texture(sky_view_table, sky_view_uv(vec3(level.x, up, level.y))).rgb;
        return ray.y <= horizon_cosine ? air : air + sun_disc(ray);
    }
    return texture(sky_view_table, sky_view_uv(ray)).rgb + sun_disc(ray);
}

void main()
{
    vec4 world = texelFetch(world_texture, ivec2(gl_FragCoord.xy), 0);
    vec3 terrain = world.a > 0.0 ? srgb_decode(world.rgb / world.a) : vec3(0.0);
    if ((through_air || sun_apart) && world.a > 0.0) {
        vec3 point = unproject(2.0 * texelFetch(world_depth, ivec2(gl_FragCoord.xy), 0).r - 1.0);
        if (sun_apart) {
            vec2 uv = ((point.xz - terrain_sun_origin) / terrain_sun_spacing + 0.5) / vec2(textureSize(terrain_sun, 0));
            terrain += texture(terrain_sun, uv).rgb * cloud_shadow_transmittance(point);
        }
        if (through_air)
            terrain = seen_through_air(terrain, 1.0, point - eye_position);
    }
    // where the terrain covers the pixel the sky is not seen: its lookups skipped
    vec3 background = world.a < 1.0 ? sky(normalize(unproject(1.0) - unproject(-1.0))) : vec3(0.0);
    frag_colour = vec4(mix(background, terrain, world.a), 1.0);
}

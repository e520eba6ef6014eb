#version 420 core
// The sky in linear RGB behind the terrain, drawn after it at the far plane: the depth test leaves out every
// pixel the terrain covers.  PHYSICAL_SKY: the atmosphere's sky-view table, the table's air less the light the
// shafts take with LIGHT_SHAFTS, or with SUN_DISC the sun's disc alone (added in a box around it: its arithmetic
// over every pixel of the sky cost llvmpipe more than the table's lookup); else a vertical gradient.  Compiled apart,
// as llvmpipe runs both sides of a branch (docs/performance.md, "The world pass: where its time goes").  The sky
// reads its tables as cloudcore/light/sky_background.py does.

#if PHYSICAL_SKY
// the atmosphere: its sky-view table (cloudcore/atmosphere/sky_view.py) seen from the scene's origin
layout(binding = 1) uniform sampler2D sky_view_table;
uniform vec2 sky_view_size;          // its (width, height): 192 x 108, 96 x 54 for a preview
uniform float zenith_horizon_angle;  // pi less the horizon's angle below the horizontal
uniform float horizon_cosine;        // the cosine to the up of the ray grazing the ground
uniform vec3 sun_direction;
uniform vec3 sun_disc_scale;         // the disc's colour per unit of its normalised radiance
uniform float pixel_angle;           // radians a pixel spans: the disc's rim is spread over it

const float SUN_ANGULAR_RADIUS = 0.004651302;  // radians(0.533 / 2), cloudcore/atmosphere/sun_disc.py
const float LIMB_DARKENING = 0.6;
const float PI = 3.14159265358979;
#if LIGHT_SHAFTS
#include "light_shafts_read.glsl"
#endif
#else
uniform vec3 zenith_colour;
uniform vec3 horizon_colour;
#endif

in vec2 ndc;
in vec3 view_ray;  // world.vert.glsl's VIEW_RAY
out vec4 frag_colour;

#if PHYSICAL_SKY
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
    // sun_disc.py's disc_radiance: the angle by its chord (acos loses it near 0 in float32), 2 asin(chord / 2)
    // by its series: within a disc's radius of the sun its next term is 1e-12 of it, and farther the disc is 0
    float chord = length(ray - sun_direction);
    float angle = chord * (1.0 + chord * chord / 24.0);
    float radius_share = min(angle / SUN_ANGULAR_RADIUS, 1.0);
    float limb = 1.0 - LIMB_DARKENING * (1.0 - sqrt(1.0 - radius_share * radius_share));
    float solid_angle = 2.0 * PI * (1.0 - cos(SUN_ANGULAR_RADIUS));
    float coverage = clamp((SUN_ANGULAR_RADIUS - angle) / max(pixel_angle, 1e-9) + 0.5, 0.0, 1.0);
    return coverage * limb / ((1.0 - LIMB_DARKENING / 3.0) * solid_angle) * sun_disc_scale;
}

vec3 sky(vec3 ray)
{
    // below the horizon the terrain stands for the ground: past the world's edge the air at the horizon is
    // drawn, as sky_background.py's over_the_horizon does (HORIZON_MARGIN), not the table's grey ground; one
    // lookup either way (both sides of a branch would be run)
    float up = horizon_cosine + 1e-3;
    float across = length(ray.xz);
    vec2 level = across > 1e-12 ? ray.xz * (sqrt(1.0 - up * up) / across) : vec2(sqrt(1.0 - up * up), 0.0);
    vec3 looked_up = ray.y < up ? vec3(level.x, up, level.y) : ray;
    vec3 air = texture(sky_view_table, sky_view_uv(looked_up)).rgb;
#if LIGHT_SHAFTS
    air = max(air - light_shafts_at(ndc).rgb, vec3(0.0));
#endif
    return air;
}
#endif

void main()
{
    vec3 ray = normalize(view_ray);
#if PHYSICAL_SKY && SUN_DISC
    // added to the sky (blended one to one); none below the horizon, where the ground hides the sun
    frag_colour = vec4(ray.y <= horizon_cosine ? vec3(0.0) : sun_disc(ray), 0.0);
#elif PHYSICAL_SKY
    frag_colour = vec4(sky(ray), 1.0);
#else
    // horizon colour at and below the horizon line; the square root keeps the pale band near the horizon
    // narrow, as in a clear sky
    frag_colour = vec4(mix(horizon_colour, zenith_colour, sqrt(clamp(ray.y, 0.0, 1.0))), 1.0);
#endif
}

#version 420 core
// The sky in linear RGB behind the terrain, drawn after it at the far plane: the depth test leaves out every
// pixel the terrain covers.  PHYSICAL_SKY: the atmosphere's sky-view table, the table's air less the light the
// shafts take with LIGHT_SHAFTS, and with FAR_GROUND the planet's ground below the horizon past the terrain; or
// with SUN_DISC the sun's disc alone (added in a box around it: its arithmetic over every pixel of the sky cost
// llvmpipe more than the table's lookup); else a vertical gradient.  Compiled apart,
// as llvmpipe runs both sides of a branch (docs/performance.md, "The world pass: where its time goes").  The sky
// reads its tables as cloudcore/light/sky_background.py does.

#if PHYSICAL_SKY
#include "sky_view.glsl"
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
#if FAR_GROUND
    // below the horizon, past the terrain's edge, the planet's ground through the air: the table's air in front of
    // it and the ground's colour through the air's transmittance to it, as sky_background.py's radiance draws it
    vec2 uv = sky_view_uv(ray);
    vec3 air = textureLod(sky_view_table, uv, 0.0).rgb;
    vec3 through = ray.y < horizon_cosine ? textureLod(sky_view_row_transmittance, vec2(0.5, uv.y), 0.0).rgb : vec3(0.0);
#else
    // a scene without a terrain: below the horizon the air at the horizon is drawn, as sky_background.py's
    // over_the_horizon does (HORIZON_MARGIN); one lookup either way (both sides of a branch would be run)
    float up = horizon_cosine + 1e-3;
    float across = length(ray.xz);
    vec2 level = across > 1e-12 ? ray.xz * (sqrt(1.0 - up * up) / across) : vec2(sqrt(1.0 - up * up), 0.0);
    vec3 looked_up = ray.y < up ? vec3(level.x, up, level.y) : ray;
    vec3 air = texture(sky_view_table, sky_view_uv(looked_up)).rgb;
#endif
#if LIGHT_SHAFTS
    air = max(air - light_shafts_at(ndc).rgb, vec3(0.0));
#endif
#if FAR_GROUND
    air += through * far_ground;
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

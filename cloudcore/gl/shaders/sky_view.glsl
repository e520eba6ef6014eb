// The atmosphere's sky-view table (cloudcore/atmosphere/sky_view.py) seen from the eye's altitude, read as its
// sky_view_uv and sky_background.py's radiance read it; with FAR_GROUND the planet's ground below the horizon too.
// gl/world.py's WorldPass binds it (unit 1, and _ROW_TRANSMITTANCE_UNIT).  GLSL 4.20 at least.
layout(binding = 1) uniform sampler2D sky_view_table;
uniform vec2 sky_view_size;          // its (width, height): 192 x 108, 96 x 54 for a preview
uniform float zenith_horizon_angle;  // pi less the horizon's angle below the horizontal
uniform float horizon_cosine;        // the cosine to the up of the ray grazing the ground
uniform vec3 sun_direction;
#if FAR_GROUND
// the planet's ground past the terrain (cloudcore/light/far_ground.py): the air's transmittance along each of the
// table's rows, and the ground's colour less the night's sky the table holds (sky_background.ground_behind_the_air)
layout(binding = 8) uniform sampler2D sky_view_row_transmittance;
uniform vec3 far_ground;
uniform vec3 night_sky;              // sky_background.NIGHT_SKY: the table's air holds it whole
#endif

vec2 sky_view_uv(vec3 ray)
{
    // sky_view.py's sky_view_uv: the zenith angle squared toward the horizon from either side (below it the
    // ground's half, read with FAR_GROUND alone), each half within its own rows, the azimuth toward the sun
    float zenith_angle = acos(clamp(ray.y, -1.0, 1.0));
    float v = 0.5 * (1.0 - sqrt(clamp(1.0 - zenith_angle / zenith_horizon_angle, 0.0, 1.0)));
    v = min(v, (0.5 * sky_view_size.y - 1.0) / (sky_view_size.y - 1.0));
#if FAR_GROUND
    if (ray.y < horizon_cosine)
    {
        float below = (zenith_angle - zenith_horizon_angle) / max(3.14159265358979 - zenith_horizon_angle, 1e-12);
        v = max(0.5 + 0.5 * sqrt(clamp(below, 0.0, 1.0)), 0.5 * sky_view_size.y / (sky_view_size.y - 1.0));
    }
#endif
    float lengths = length(ray.xz) * length(sun_direction.xz);
    float light_view_cosine = lengths > 1e-12 ? clamp(dot(ray.xz, sun_direction.xz) / lengths, -1.0, 1.0) : 1.0;
    float u = sqrt(clamp(0.5 - 0.5 * light_view_cosine, 0.0, 1.0));
    // table_sampling.py's unit_to_sub_uv
    return (vec2(u, v) + 0.5 / sky_view_size) * (sky_view_size / (sky_view_size + 1.0));
}

#if FAR_GROUND
// the air between the eye and the planet's ground along unit `ray` below the horizon: its transmittance and the
// light it adds as the air's volume gives them (aerial_perspective.glsl's air_toward: the night's sky where it hides
// the ground); textureLod, as a vertex shader has no derivatives
void air_to_the_ground(vec3 ray, out vec3 transmittance, out vec3 in_scattered)
{
    vec2 uv = sky_view_uv(ray);
    transmittance = textureLod(sky_view_row_transmittance, vec2(0.5, uv.y), 0.0).rgb;
    in_scattered = textureLod(sky_view_table, uv, 0.0).rgb - night_sky * transmittance;
}
#endif

// The air between the eye and a point: cloudcore/atmosphere/aerial_perspective.py's volume, read as its
// volume_uvw and cloudcore/light/air_between.py's seen_through do (cloudcore/gl/air_volume.py binds it to the
// units here, AIR_UNITS: declared, so that no program that includes it has two kinds of sampler on one unit).
// GLSL 4.20 at least.
layout(binding = 3) uniform sampler3D air_in_scattered;   // the light added, the renderer's values
layout(binding = 4) uniform sampler3D air_transmittance;
uniform vec3 air_sun_direction;
uniform vec3 air_volume_size;         // (azimuth, cosine to the up, distance) texels
uniform float air_max_distance;       // metres, the last slice's

// the texture coordinates (u, v) of the direction `direction` (unit), w of the distance `distance` (metres)
vec2 air_direction_uv(vec3 direction)
{
    float lengths = length(direction.xz) * length(air_sun_direction.xz);
    float light_view_cosine = lengths > 1e-12 ? clamp(dot(direction.xz, air_sun_direction.xz) / lengths, -1.0, 1.0) : 1.0;
    float azimuth = sqrt(clamp(0.5 - 0.5 * light_view_cosine, 0.0, 1.0));
    float mu = clamp(direction.y, -1.0, 1.0);
    float up = 0.5 + 0.5 * sign(mu) * sqrt(abs(mu));
    // table_sampling.py's unit_to_sub_uv: the unit range onto the first to the last texel's centre
    return (vec2(azimuth, up) + 0.5 / air_volume_size.xy) * (air_volume_size.xy / (air_volume_size.xy + 1.0));
}

float air_distance_w(float distance)
{
    float slice_position = sqrt(clamp(distance / air_max_distance, 0.0, 1.0));
    return (slice_position + 0.5 / air_volume_size.z) * (air_volume_size.z / (air_volume_size.z + 1.0));
}

vec3 air_uvw(vec3 from_eye)
{
    float distance = length(from_eye);
    return vec3(air_direction_uv(from_eye / max(distance, 1e-6)), air_distance_w(distance));
}

// the air's transmittance and the light it adds between the eye and `from_eye` (the point less the eye, metres);
// textureLod, as a compute or vertex shader has no derivatives to choose a level by
void air_toward(vec3 from_eye, out vec3 transmittance, out vec3 in_scattered)
{
    vec3 uvw = air_uvw(from_eye);
    transmittance = textureLod(air_transmittance, uvw, 0.0).rgb;
    in_scattered = textureLod(air_in_scattered, uvw, 0.0).rgb;
}

// premultiplied `colour` of opacity `alpha` at `from_eye` seen through the air
vec3 seen_through_air(vec3 colour, float alpha, vec3 from_eye)
{
    vec3 transmittance, in_scattered;
    air_toward(from_eye, transmittance, in_scattered);
    return colour * transmittance + alpha * in_scattered;
}

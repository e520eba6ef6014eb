#version 420 core
// The terrain's tiles (cloudcore/world/terrain_tiles.py) lit as cloudcore/light/terrain_light.py lights them, per
// vertex: the sun's part apart from the sky's (the clouds' shadow dims the sun's alone, per pixel).  With
// THROUGH_AIR the air between the eye and each vertex is read here, per vertex, not per pixel, and with
// LIGHT_SHAFTS the light shafts' share of its light taken off: a pixel's lookups cost llvmpipe more than the
// vertices' (docs/performance.md, "The world pass: where its time goes").

layout(location = 0) in vec3 position;
layout(location = 1) in vec3 sun_light;  // albedo x the sun's irradiance, linear RGB
layout(location = 2) in vec3 sky_light;  // albedo x the sky's dome, the ground's bounce and the floor
uniform mat4 view_projection;
uniform vec3 eye_position;

// what the eye sees of the vertex: the sun's part (which the clouds' shadow dims per pixel) and the rest with the
// air's light, both through the air; two varyings where the light and the air were four (each varying a pixel
// interpolates cost llvmpipe: docs/atmosphere.md#the-shafts-cheaper-issue-52s-budget)
out vec3 sun_seen;
out vec3 rest_seen;
#if CLOUD_SHADOW_READ && BAKED_SHADOW
// where the shadow's baked texture is read, per pixel (terrain.frag.glsl), affine in the world's coordinates too
out vec2 ground_shadow_uv;
uniform mat4 world_to_ground_shadow;  // cloudcore/light/ground_shadows.py's world_to_texture
#elif CLOUD_SHADOW_READ
// where the clouds' shadow map is read, per pixel (terrain.frag.glsl): the map's coordinates are affine in the
// world's, so the vertices' interpolate to each pixel's exactly, without the matrix a pixel
out vec3 shadow_mapped;
uniform mat4 world_to_cloud_shadow;  // cloud_shadow.glsl's
#endif

#if THROUGH_AIR
#include "aerial_perspective.glsl"
#endif
#if FAR_GROUND
// compiled for the tiles that reach past far_air_from alone (cloudcore/gl/world.py): llvmpipe runs a branch's both
// sides, so every vertex would pay the sky table's reads (docs/performance.md, "The terrain's triangles on llvmpipe")
#include "sky_view.glsl"
uniform float far_air_from;  // aerial_perspective.FAR_AIR_FROM of air_max_distance, metres
#endif
#if LIGHT_SHAFTS
#include "light_shafts_read.glsl"
#endif

void main()
{
    gl_Position = view_projection * vec4(position, 1.0);
#if CLOUD_SHADOW_READ && BAKED_SHADOW
    ground_shadow_uv = (world_to_ground_shadow * vec4(position, 1.0)).xy;
#elif CLOUD_SHADOW_READ
    shadow_mapped = (world_to_cloud_shadow * vec4(position, 1.0)).xyz;
#endif
    vec3 air_let_through, air_added;
#if THROUGH_AIR
    air_toward(position - eye_position, air_let_through, air_added);
#if FAR_GROUND
    // the air's volume ends at air_max_distance; past it the sky draws the planet's ground through the air it
    // tables to the ground: from far_air_from on the terrain's air turns into that one, so that the
    // terrain's edge, anywhere past the volume, meets the ground drawn past it without a line (a vertex over the
    // horizon keeps the volume's: the table's rays there do not end on the ground)
    vec3 from_eye = position - eye_position;
    float beyond = smoothstep(far_air_from, air_max_distance, length(from_eye));
    vec3 ray = normalize(from_eye);
    if (beyond > 0.0 && ray.y < horizon_cosine) {
        vec3 far_let_through, far_added;
        air_to_the_ground(ray, far_let_through, far_added);
        air_let_through = mix(air_let_through, far_let_through, beyond);
        air_added = mix(air_added, far_added, beyond);
    }
#endif
#if LIGHT_SHAFTS
    // read where the vertex falls on the screen (the shafts change little across a triangle); none behind the
    // eye, where the air is the eye's own
    if (gl_Position.w > 0.0)
        air_added *= 1.0 - light_shafts_at(clamp(gl_Position.xy / gl_Position.w, -1.0, 1.0)).a;
#endif
#else
    air_let_through = vec3(1.0);
    air_added = vec3(0.0);
#endif
    sun_seen = sun_light * air_let_through;
    rest_seen = sky_light * air_let_through + air_added;
}

#version 420 core
// The physical sky at the screen's resolution, read bilinearly from its picture at a fraction of it
// (sky.frag.glsl into `WorldPass`'s sky target, the shafts' light already taken off): the sky changes slowly
// across the screen, and a pixel's table lookup cost llvmpipe more than one fetch (docs/atmosphere.md, "The sky
// at a fraction of the resolution").  Drawn at the far plane, after the terrain, where the depth test leaves it.
// With FAR_GROUND the planet's ground that the sky draws below the horizon past the terrain is given its depth, so
// that a cloud behind it is hidden as behind the terrain (docs/atmosphere.md, "The ground past the terrain"), and
// with FAR_GROUND_SHADOWS its sun's part in the clouds' shadows, read at the screen's resolution as the terrain's:
// the picture's 128 columns would blur them (docs/atmosphere.md, "The far ground's cloud shadows").

layout(binding = 2) uniform sampler2D sky_picture;

in vec2 ndc;
out vec4 frag_colour;

#if FAR_GROUND
in vec3 view_ray;             // world.vert.glsl's VIEW_RAY
// (the eye's altitude over the planet's ground lowered under the terrain's lowest vertex, its radius), metres:
// the terrain always stands in front of it, so this pass never draws over the terrain (world.py's
// WorldPass._ground_below_the_terrain)
uniform vec2 planet_ground;
uniform vec3 view_forward;    // the view's forward, unit
uniform vec2 depth_terms;     // the projection's [2][2] and [2][3]
#include "planet_ground.glsl"
#endif
#if FAR_GROUND_SHADOWS
#include "sky_view.glsl"
#include "cloud_shadow.glsl"
uniform vec3 far_ground_sun;  // the far ground's sun part (far_ground.py's far_ground_sun), renderer values
uniform vec3 eye;             // world metres
uniform float far_ground_y;   // world metres: the level of the far ground (its edge's), where it reads the map
#endif

void main()
{
    frag_colour = vec4(textureLod(sky_picture, 0.5 * ndc + 0.5, 0.0).rgb, 1.0);
#if FAR_GROUND
    vec3 ray = normalize(view_ray);
    // the ground's distance along the view's forward, and its window depth as the projection gives it (past the
    // far plane, the far plane's)
    float ahead = distance_to_ground(planet_ground.x, planet_ground.y, ray.y) * dot(ray, view_forward);
    gl_FragDepth = ahead < 1.0e30 ? clamp(0.5 - 0.5 * (depth_terms.x - depth_terms.y / ahead), 0.0, 1.0) : 1.0;
#if FAR_GROUND_SHADOWS
    // the shadow falls on the level ground the far ground's colour is of, where the ray meets it (the terrain's
    // edge is there: no step in the shadow across it); off the map, behind no cloud, the map reads 1
    if (ahead < 1.0e30 && ray.y < 0.0 && cloud_shadows)
    {
        vec3 ground = eye + ray * ((eye.y - far_ground_y) / -ray.y);
        vec3 through = textureLod(sky_view_row_transmittance, vec2(0.5, sky_view_uv(ray).y), 0.0).rgb;
        float shadowed = 1.0 - cloud_shadow_transmittance(ground);
        frag_colour.rgb = max(frag_colour.rgb - shadowed * through * far_ground_sun, vec3(0.0));
    }
#endif
#endif
}

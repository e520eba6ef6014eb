#version 420 core
// The physical sky at the screen's resolution, read bilinearly from its picture at a fraction of it
// (sky.frag.glsl into `WorldPass`'s sky target, the shafts' light already taken off): the sky changes slowly
// across the screen, and a pixel's table lookup cost llvmpipe more than one fetch (docs/atmosphere.md, "The sky
// at a fraction of the resolution").  Drawn at the far plane, after the terrain, where the depth test leaves it.
// With FAR_GROUND the planet's ground that the sky draws below the horizon past the terrain is given its depth, so
// that a cloud behind it is hidden as behind the terrain (docs/atmosphere.md, "The ground past the terrain").

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

void main()
{
    frag_colour = vec4(textureLod(sky_picture, 0.5 * ndc + 0.5, 0.0).rgb, 1.0);
#if FAR_GROUND
    vec3 ray = normalize(view_ray);
    // the ground's distance along the view's forward, and its window depth as the projection gives it (past the
    // far plane, the far plane's)
    float ahead = distance_to_ground(planet_ground.x, planet_ground.y, ray.y) * dot(ray, view_forward);
    gl_FragDepth = ahead < 1.0e30 ? clamp(0.5 - 0.5 * (depth_terms.x - depth_terms.y / ahead), 0.0, 1.0) : 1.0;
#endif
}

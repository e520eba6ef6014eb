#version 420 core
// The terrain's colour in linear RGB, its sun's part in the clouds' shadow at the pixel (cloud_shadow.glsl), seen
// through the air its vertices read (terrain.vert.glsl).

in vec3 sun_lit;
in vec3 sky_lit;
in vec3 shadow_mapped;  // the pixel's place in the clouds' transmittance map (terrain.vert.glsl)
in vec3 air_let_through;
in vec3 air_added;
out vec4 frag_colour;
#include "cloud_shadow.glsl"

void main()
{
    vec3 lit = sun_lit * (cloud_shadows ? cloud_shadow_transmittance_mapped(shadow_mapped) : 1.0) + sky_lit;
    frag_colour = vec4(lit * air_let_through + air_added, 1.0);
}

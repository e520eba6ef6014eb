#version 420 core
// The terrain's colour in linear RGB, its sun's part in the clouds' shadow at the pixel (cloud_shadow.glsl), seen
// through the air its vertices read (terrain.vert.glsl).

in vec3 sun_seen;       // the sun's part, through the air
in vec3 rest_seen;      // the sky's part through the air, and the air's light
in vec3 shadow_mapped;  // the pixel's place in the clouds' transmittance map (terrain.vert.glsl)
out vec4 frag_colour;
#include "cloud_shadow.glsl"

void main()
{
    float sunlit = cloud_shadows ? cloud_shadow_transmittance_mapped(shadow_mapped) : 1.0;
    frag_colour = vec4(sun_seen * sunlit + rest_seen, 1.0);
}

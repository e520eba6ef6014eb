#version 420 core
// The share of the sun the clouds let reach the ground at a texel's centre (cloud_shadow.glsl's read of their map),
// which the terrain's pixels then read with one fetch (terrain.frag.glsl).

in vec3 shadow_mapped;
out vec4 frag_colour;
#include "cloud_shadow.glsl"

void main()
{
    frag_colour = vec4(cloud_shadow_transmittance_mapped(shadow_mapped));
}

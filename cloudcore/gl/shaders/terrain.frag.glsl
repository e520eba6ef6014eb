#version 420 core
// The terrain's colour in linear RGB, its sun's part in the clouds' shadow at the pixel (cloud_shadow.glsl), seen
// through the air its vertices read (terrain.vert.glsl).  Without CLOUD_SHADOW_READ, for the tiles off the clouds'
// map (cloudcore/world/terrain_tiles.py's under_the_clouds_map), the sun's part whole: llvmpipe runs a read under a
// false condition all the same (docs/performance.md, "The terrain's pixels off the clouds' map").  With
// BAKED_SHADOW the shadow is one fetch of the texture it is baked into over the ground (ground_shadow_bake.*.glsl,
// cloudcore/light/ground_shadows.py): the map's read, two fetches and an exponential, cost llvmpipe about a third of
// the draw (docs/performance.md, "The clouds' shadow baked on the ground").

in vec3 sun_seen;       // the sun's part, through the air
in vec3 rest_seen;      // the sky's part through the air, and the air's light
out vec4 frag_colour;
#if CLOUD_SHADOW_READ && BAKED_SHADOW
in vec2 ground_shadow_uv;  // the pixel's place in the baked texture (terrain.vert.glsl)
// the share of the sun the clouds let through, 8 bits: llvmpipe's bilinear fetch of 8-bit texels is its cheapest
// (cloudcore/gl/ground_shadows.py's GROUND_SHADOW_UNIT)
layout(binding = 9) uniform sampler2D ground_shadow;
#elif CLOUD_SHADOW_READ
in vec3 shadow_mapped;  // the pixel's place in the clouds' transmittance map (terrain.vert.glsl)
#include "cloud_shadow.glsl"
#endif

void main()
{
#if CLOUD_SHADOW_READ && BAKED_SHADOW
    frag_colour = vec4(sun_seen * textureLod(ground_shadow, ground_shadow_uv, 0.0).r + rest_seen, 1.0);
#elif CLOUD_SHADOW_READ
    float sunlit = cloud_shadows ? cloud_shadow_transmittance_mapped(shadow_mapped) : 1.0;
    frag_colour = vec4(sun_seen * sunlit + rest_seen, 1.0);
#else
    frag_colour = vec4(sun_seen + rest_seen, 1.0);
#endif
}

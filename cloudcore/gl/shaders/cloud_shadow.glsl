// The clouds' transmittance map (cloudcore/gl/shadow_map.py): the share of the sun's beam the clouds let reach a
// point, as cloudcore/light/cloud_shadows.py's sample_map reads it (bilinear between texel centres, none off the
// map, linear between slices).  Units 5 and 6: cloudcore.gl.shadow_map.SHADOW_UNITS.
uniform bool cloud_shadows;
layout(binding = 5) uniform sampler2D cloud_shadow_slices_1_to_4;
layout(binding = 6) uniform sampler2D cloud_shadow_slices_5_to_8;
uniform mat4 world_to_cloud_shadow;  // world to (u, v, slice coordinate, 1)

// at `mapped`, a point's (u, v, slice coordinate) in the map (world_to_cloud_shadow's); textureLod, as a vertex
// shader has no derivatives and the map no levels to choose between
float cloud_shadow_transmittance_mapped(vec3 mapped)
{
    float s = clamp(mapped.z, 0.0, 8.0);
    if (s <= 0.0)
        return 1.0;
    vec4 far = textureLod(cloud_shadow_slices_5_to_8, mapped.xy, 0.0);
    if (s >= 8.0)  // behind every cloud, as the ground mostly is: one fetch
        return exp(-far.w);
    vec4 near = textureLod(cloud_shadow_slices_1_to_4, mapped.xy, 0.0);
    // linear between the slices' depths (0 at s = 0, slice k's at s = k) as a sum of each span's rise times how much
    // of it lies below s: an array indexed per pixel cost the light shafts' march more
    // (docs/atmosphere.md#the-shafts-cheaper-issue-52s-budget)
    vec4 near_rise = near - vec4(0.0, near.xyz);
    vec4 far_rise = far - vec4(near.w, far.xyz);
    vec4 covered_near = clamp(vec4(s) - vec4(0.0, 1.0, 2.0, 3.0), 0.0, 1.0);
    vec4 covered_far = clamp(vec4(s) - vec4(4.0, 5.0, 6.0, 7.0), 0.0, 1.0);
    return exp(-(dot(covered_near, near_rise) + dot(covered_far, far_rise)));
}

float cloud_shadow_transmittance(vec3 world)
{
    if (!cloud_shadows)
        return 1.0;
    return cloud_shadow_transmittance_mapped((world_to_cloud_shadow * vec4(world, 1.0)).xyz);
}

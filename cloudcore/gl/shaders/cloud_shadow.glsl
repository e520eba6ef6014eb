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
    float depths[9] = float[9](0.0, near.x, near.y, near.z, near.w, far.x, far.y, far.z, far.w);
    int below = min(int(s), 7);
    return exp(-mix(depths[below], depths[below + 1], s - float(below)));
}

float cloud_shadow_transmittance(vec3 world)
{
    if (!cloud_shadows)
        return 1.0;
    return cloud_shadow_transmittance_mapped((world_to_cloud_shadow * vec4(world, 1.0)).xyz);
}

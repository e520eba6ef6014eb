#version 330 core
// One particle of the clouds' transmittance map (cloudcore/light/cloud_shadows.py): a square over its disc,
// widened to a texel where it is narrower, seen along the sun.  Triangle-strip corners from gl_VertexID, or with
// POINTS one point sprite of the square's side (the view is orthographic: the same texels).

layout(location = 0) in vec3 centre;
layout(location = 1) in float radius;
layout(location = 2) in float particle_opacity;

uniform mat4 world_to_map;  // world to (u, v, slice coordinate, 1): LightSpace.world_to_map
uniform float texel_m;      // a texel's side
uniform vec2 map_size;      // texels across, up
uniform float slice_m;      // a slice's depth

out vec2 offset;             // from the particle's centre, in (widened) radii (a point's: gl_PointCoord)
flat out float opacity;      // what the particle takes out of the sun's beam at its centre
flat out float scale;        // what keeps the optical depth's integral where the particle is widened
flat out float slice_centre;
flat out float slice_half;   // the slab's half thickness, in slices

void main()
{
#ifdef POINTS
    vec2 corner = vec2(0.0);
#else
    vec2 corner = vec2(gl_VertexID & 1, gl_VertexID >> 1) * 2.0 - 1.0;
#endif
    vec3 mapped = (world_to_map * vec4(centre, 1.0)).xyz;
    float wide = max(radius, texel_m);
    offset = corner;
    opacity = particle_opacity;
    scale = (radius / wide) * (radius / wide);
    slice_centre = mapped.z;
    slice_half = radius / slice_m;
    vec2 uv = mapped.xy + corner * wide / (texel_m * map_size);
    gl_Position = vec4(2.0 * uv - 1.0, 0.0, 1.0);
#ifdef POINTS
    gl_PointSize = 2.0 * wide / texel_m;
#endif
}

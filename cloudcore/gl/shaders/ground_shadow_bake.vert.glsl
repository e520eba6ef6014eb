#version 420 core
// The terrain's tiles seen from above, laid over the texture of the clouds' shadow on the ground
// (cloudcore/gl/ground_shadows.py): a vertex's place on the ground is its place in the texture, its place along the
// sun its place in the clouds' transmittance map.

layout(location = 0) in vec3 position;
uniform mat4 world_to_ground_shadow;  // world to (u, v, 0, 1) over the texture
uniform mat4 world_to_cloud_shadow;   // cloud_shadow.glsl's
out vec3 shadow_mapped;

void main()
{
    vec2 uv = (world_to_ground_shadow * vec4(position, 1.0)).xy;
    gl_Position = vec4(2.0 * uv - 1.0, 0.0, 1.0);
    // affine in the world's coordinates: the vertices' interpolate to each texel's exactly
    shadow_mapped = (world_to_cloud_shadow * vec4(position, 1.0)).xyz;
}

#version 430 core
// The clouds' nearest depth at the light shafts' march resolution (Yusov's cut,
// docs/atmosphere.md#the-shafts-and-the-air-in-front-of-the-clouds): each particle of a drawn cloud a point over
// the core of its disc (CORE of its radius: cloudcore.gl.splats.NEAREST_DEPTH_CORE) at its centre's depth, read
// from the resident particles (cloudcore.gl.splat_residency's `Particle`, PARTICLE_FLOATS floats each) and their
// opacity factors (a formation, a field's blend weights); a particle too faint to be seen is left out, as the air
// behind it is the sky's.

layout(std430, binding = 0) readonly buffer Particles { float particle_floats[]; };
layout(std430, binding = 1) readonly buffer Formation { float formation[]; };
layout(std430, binding = 2) readonly buffer Chosen { uint chosen[]; };  // cloudcore.light.light_shafts.nearest_depth_particles

uniform mat4 view_projection;  // of points relative to the eye
uniform vec3 eye_position;
uniform float pixels_per_ndc;  // half the target's height over the projection's [1][1]: a radius's pixels at w 1

void main()
{
    int particle = int(chosen[gl_VertexID]);
    int record = particle * PARTICLE_FLOATS;
    vec3 centre = vec3(particle_floats[record], particle_floats[record + 1], particle_floats[record + 2]);
    float radius = particle_floats[record + 3];
    float opacity = particle_floats[record + 7] * formation[particle];
    gl_Position = view_projection * vec4(centre - eye_position, 1.0);
    gl_PointSize = clamp(2.0 * CORE * radius * pixels_per_ndc / max(gl_Position.w, 1e-6), 1.0, MAX_POINT_SIZE);
    if (opacity < SEEN_OPACITY || gl_Position.w <= 0.0)
        gl_Position = vec4(0.0, 0.0, 2.0, 1.0);  // outside the clip volume: no fragment
}

#version 330 core
// A camera-facing square of side 2r around each particle: the corner offset is
// added in eye space, so the square always lies parallel to the image plane.

layout(location = 0) in vec2 corner;         // (+-1, +-1)
layout(location = 1) in vec4 centre_radius;  // world xyz, radius
layout(location = 2) in vec4 colour_alpha;   // premultiplied linear rgb, opacity

uniform mat4 view;
uniform mat4 projection;

out vec2 splat_position;  // corner in radii: the kernel's d = length(splat_position)
flat out vec4 particle;

void main()
{
    vec4 centre = view * vec4(centre_radius.xyz, 1.0);
    gl_Position = projection * (centre + vec4(corner * centre_radius.w, 0.0, 0.0));
    splat_position = corner;
    particle = colour_alpha;
}

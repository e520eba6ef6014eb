#version 430 core
// Draws the quads splat_shade.comp.glsl built: four vertices per particle,
// as indexed triangles rather than instances (a software rasteriser runs its
// vertex pipeline once per instance).  Corners come relative to the eye,
// so the view matrix applies without its translation.

struct Instance {
    vec4 corners[4];  // relative to the eye; w: atlas cell (-1: Gaussian splat)
    vec4 colours[4];  // premultiplied linear rgb, opacity
};
layout(std430, binding = 3) readonly buffer Instances { Instance instances[]; };

uniform mat4 view_rotation;  // the view matrix without its translation
uniform mat4 projection;

out vec2 splat_position;  // corner in radii: the kernel's d = length(splat_position)
out vec4 colour;          // per corner: the artist model's varies up a sprite
flat out int sprite;      // atlas cell, -1 for a Gaussian splat

const vec2 CORNERS[4] = vec2[](vec2(-1.0, -1.0), vec2(1.0, -1.0), vec2(-1.0, 1.0), vec2(1.0, 1.0));

void main()
{
    int slot = gl_VertexID >> 2, k = gl_VertexID & 3;
    vec4 corner = instances[slot].corners[k];
    gl_Position = projection * (view_rotation * vec4(corner.xyz, 1.0));
    splat_position = CORNERS[k];
    colour = instances[slot].colours[k];
    sprite = int(corner.w);
}

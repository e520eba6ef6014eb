#version 420 core
// The physical sky at the screen's resolution, read bilinearly from its picture at a fraction of it
// (sky.frag.glsl into `WorldPass`'s sky target, the shafts' light already taken off): the sky changes slowly
// across the screen, and a pixel's table lookup cost llvmpipe more than one fetch (docs/atmosphere.md, "The sky
// at a fraction of the resolution").  Drawn at the far plane, after the terrain, where the depth test leaves it.

layout(binding = 2) uniform sampler2D sky_picture;

in vec2 ndc;
out vec4 frag_colour;

void main()
{
    frag_colour = vec4(textureLod(sky_picture, 0.5 * ndc + 0.5, 0.0).rgb, 1.0);
}

#version 330 core
// The frame's linear colour to 8-bit sRGB for the editor's viewport: the GPU
// twin of cloudcore.colour.linear_to_srgb8 (clamp to [0, 1], NaN to 0, then
// the IEC 61966-2-1 transfer), drawn over the screen triangle of world.vert.

uniform sampler2D frame;
out vec4 frag_colour;

vec3 srgb_encode(vec3 linear)
{
    vec3 low = 12.92 * linear;
    vec3 high = 1.055 * pow(linear, vec3(1.0 / 2.4)) - 0.055;
    return mix(high, low, lessThanEqual(linear, vec3(0.0031308)));
}

void main()
{
    vec3 linear = texelFetch(frame, ivec2(gl_FragCoord.xy), 0).rgb;
    linear = clamp(mix(linear, vec3(0.0), isnan(linear)), 0.0, 1.0);
    frag_colour = vec4(srgb_encode(linear), 1.0);
}

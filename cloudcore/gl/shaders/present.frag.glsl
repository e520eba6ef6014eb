#version 330 core
// The frame's linear colour to 8-bit sRGB for the editor's viewport: the GPU
// twin of cloudcore.maths.colour.linear_to_srgb8 (clamp to [0, 1], NaN to 0, the
// IEC 61966-2-1 transfer, then the same 4x4 ordered dither: each pixel rounds
// down past its own threshold, written as an exact level of the RGBA8 target),
// drawn over the screen triangle of world.vert.

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
    const float bayer[16] = float[16](0.0, 8.0, 2.0, 10.0, 12.0, 4.0, 14.0, 6.0,
                                      3.0, 11.0, 1.0, 9.0, 15.0, 7.0, 13.0, 5.0);
    ivec2 cell = ivec2(gl_FragCoord.xy) % 4;
    float threshold = (bayer[4 * cell.y + cell.x] + 0.5) / 16.0;
    vec3 level = clamp(floor(srgb_encode(linear) * 255.0 + threshold), 0.0, 255.0);
    frag_colour = vec4(level / 255.0, 1.0);
}

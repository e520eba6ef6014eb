#version 420 core
// The light shafts' march blurred by a 3x3 tent (1 2 1 across, 1 2 1 down) at its own resolution: each march pixel
// reads its steps' transmittance at its own dithered offset (light_shafts.frag.glsl), and read alone the dither's
// pattern showed through the sky where a ray's steps are hundreds of metres; averaged over its neighbours' offsets
// it does not.

layout(binding = 0) uniform sampler2D march;
out vec4 blurred;

void main()
{
    ivec2 pixel = ivec2(gl_FragCoord.xy);
    ivec2 last = textureSize(march, 0) - 1;
    vec4 sum = vec4(0.0);
    for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx)
            sum += float((2 - abs(dx)) * (2 - abs(dy))) * texelFetch(march, clamp(pixel + ivec2(dx, dy), ivec2(0), last), 0);
    blurred = sum / 16.0;
}

#version 330 core
// The world in linear RGB: pyrender's terrain over a vertical sky gradient.
//
// pyrender drew sRGB-encoded vertex colours (8 bits are too coarse for linear
// colour in the shadows) over a transparent black background, and multisample
// resolve averaged them with it: a pixel holds (coverage * colour, coverage).

uniform sampler2D world_texture;
uniform mat4 inverse_view_projection;
uniform vec3 zenith_colour;
uniform vec3 horizon_colour;

in vec2 ndc;
out vec4 frag_colour;

vec3 srgb_decode(vec3 encoded)
{
    vec3 low = encoded / 12.92;
    vec3 high = pow((encoded + 0.055) / 1.055, vec3(2.4));
    return mix(high, low, lessThanEqual(encoded, vec3(0.04045)));
}

vec3 unproject(float depth)
{
    vec4 world = inverse_view_projection * vec4(ndc, depth, 1.0);
    return world.xyz / world.w;
}

vec3 sky(vec3 ray)
{
    // horizon colour at and below the horizon line; the square root keeps the
    // pale band near the horizon narrow, as in a clear sky
    return mix(horizon_colour, zenith_colour, sqrt(clamp(ray.y, 0.0, 1.0)));
}

void main()
{
    vec4 world = texelFetch(world_texture, ivec2(gl_FragCoord.xy), 0);
    vec3 terrain = world.a > 0.0 ? srgb_decode(world.rgb / world.a) : vec3(0.0);
    vec3 background = sky(normalize(unproject(1.0) - unproject(-1.0)));
    frag_colour = vec4(mix(background, terrain, world.a), 1.0);
}

#version 420 core
// pyrender's picture of some objects, composited into the linear frame at their own depth.
//
// pyrender wrote pow(linear, 1/2.2) over transparent black and multisample
// resolve averaged it with the background: a pixel holds (coverage * encoded,
// coverage).  The depth test (against the frame's depth) keeps terrain in front.  Under the physical sky
// they are seen through the air between them and the eye (aerial_perspective.glsl), as the terrain is.  Where the
// clouds shadow them, object_colour is their picture lit by the lights but the sun, object_sun by the sun alone,
// which the clouds' transmittance map at each pixel's place scales (cloud_shadow.glsl).

layout(binding = 0) uniform sampler2D object_colour;
layout(binding = 1) uniform sampler2D object_depth;
layout(binding = 2) uniform sampler2D object_sun;
uniform bool through_air;
uniform bool sun_apart;
uniform mat4 inverse_view_projection;
uniform vec3 eye_position;
#include "aerial_perspective.glsl"
#include "cloud_shadow.glsl"

in vec2 ndc;
out vec4 frag_colour;

void main()
{
    ivec2 texel = ivec2(gl_FragCoord.xy);
    vec4 objects = texelFetch(object_colour, texel, 0);
    if (objects.a <= 0.0)
        discard;
    float depth = texelFetch(object_depth, texel, 0).r;
    gl_FragDepth = depth;
    // premultiplied by coverage, as the blend expects
    vec3 colour = pow(objects.rgb / objects.a, vec3(2.2)) * objects.a;
    if (through_air || sun_apart) {
        vec4 point = inverse_view_projection * vec4(ndc, 2.0 * depth - 1.0, 1.0);
        vec3 place = point.xyz / point.w;
        if (sun_apart) {
            vec4 sun = texelFetch(object_sun, texel, 0);
            if (sun.a > 0.0)
                colour += pow(sun.rgb / sun.a, vec3(2.2)) * sun.a * cloud_shadow_transmittance(place);
        }
        if (through_air)
            colour = seen_through_air(colour, objects.a, place - eye_position);
    }
    frag_colour = vec4(colour, objects.a);
}

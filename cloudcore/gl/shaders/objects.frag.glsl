#version 330 core
// pyrender's picture of some objects, composited into the linear frame at their own depth.
//
// pyrender wrote pow(linear, 1/2.2) over transparent black and multisample
// resolve averaged it with the background: a pixel holds (coverage * encoded,
// coverage).  The depth test (against the frame's depth) keeps terrain in front.

uniform sampler2D object_colour;
uniform sampler2D object_depth;

in vec2 ndc;
out vec4 frag_colour;

void main()
{
    ivec2 texel = ivec2(gl_FragCoord.xy);
    vec4 objects = texelFetch(object_colour, texel, 0);
    if (objects.a <= 0.0)
        discard;
    gl_FragDepth = texelFetch(object_depth, texel, 0).r;
    // premultiplied by coverage, as the blend expects
    frag_colour = vec4(pow(objects.rgb / objects.a, vec3(2.2)) * objects.a, objects.a);
}

#version 420 core
// Premultiplied colour from an impostor texture, scaled by its share of the
// cloud's opacity, plus (in a crossfade) the full-3D image of the same cloud
// from a screen-sized layer scaled by the rest: a linear mix of two
// premultiplied images is itself a correct premultiplied image, so the
// crossfade neither brightens nor darkens.  Only the CROSSFADE variant reads the
// layer: behind a branch on a uniform, llvmpipe paid for the fetch on every
// quad that never took it (7% of the flythrough's clouds, docs/journal.md, "The level of detail by error
// and cost", eighth session).
// ATLAS samples a layer of the impostor atlas within the instance's cell, its
// weight per instance.  COUNT_FRAGMENTS writes 1 instead.  AIR adds the air between the eye
// and the quad now (quad.vert.glsl's, interpolated) to the impostor's part (aerial perspective: never in an impostor's texture, which is
// seen from elsewhere; the crossfade's layer has it already, per particle, from this eye).

#ifdef ATLAS
uniform sampler2DArray impostor;
flat in vec4 clamp_rect;
flat in vec2 weight_layer;
#else
uniform sampler2D impostor;
uniform float impostor_weight;
#endif
uniform sampler2D layer;
uniform float layer_weight;
#ifdef AIR
in vec3 air_transmittance_at;  // quad.vert.glsl's, at the corners of the quad's cells
in vec3 air_in_scattered_at;
#endif

in vec2 uv;
out vec4 frag_colour;

void main()
{
#ifdef COUNT_FRAGMENTS
    frag_colour = vec4(1.0);
#else
#ifdef ATLAS
    float weight = weight_layer.x;
    vec4 colour = texture(impostor, vec3(clamp(uv, clamp_rect.xy, clamp_rect.zw), weight_layer.y));
#else
    float weight = impostor_weight;
    vec4 colour = texture(impostor, uv);
#endif
    // a weight over 1 (a field's cloud faded in since its impostor was made: FrameRenderer._faded) never makes
    // an opacity over 1, which would darken what lies behind it
    colour *= min(weight, 1.0 / max(colour.a, 1e-6));
#ifdef AIR
    colour.rgb = colour.rgb * air_transmittance_at + colour.a * air_in_scattered_at;
#endif
#ifdef CROSSFADE
    colour += layer_weight * texelFetch(layer, ivec2(gl_FragCoord.xy), 0);
#endif
    frag_colour = colour;
#endif
}

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
// seen from elsewhere; the crossfade's layer has it already, per particle, from this eye).  PANEL_DEPTH: a
// ring panel's fragment put at the depth of its segment's nearest particle on the ray from the ring's eye
// (panel_depth, drawn through the segment's camera: near and far planes segment_near_far), not at the panel's:
// the panel stands at the ring's radius, and terrain beyond it hid its clouds in full 3D but not on the panel
// (docs/lod.md, "Wang's ring").

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

#ifdef PANEL_DEPTH
uniform sampler2D panel_depth;
uniform vec3 panel_eye;  // the ring's eye, where the segment was seen from
uniform float panel_distance;  // metres from panel_eye to the panel along its segment's middle
uniform vec2 segment_near_far;
uniform mat4 view_projection;
in vec3 panel_point;
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
#ifdef PANEL_DEPTH
    float stored = texture(panel_depth, uv).r;
    float depth = gl_FragCoord.z;
    if (stored < 1.0) {
        // the segment camera's depth back to metres along its axis, the panel's point moved along the ray from
        // the ring's eye to that distance, and projected into this frame
        float near = segment_near_far.x, far = segment_near_far.y;
        float along = 2.0 * near * far / (far + near - (2.0 * stored - 1.0) * (far - near));
        vec4 clip = view_projection * vec4(panel_eye + (panel_point - panel_eye) * (along / panel_distance), 1.0);
        if (clip.w > 0.0)
            depth = clamp(0.5 * clip.z / clip.w + 0.5, 0.0, 1.0);
    }
    gl_FragDepth = depth;
#endif
}

#version 330 core
// The splat kernel of cloudcore.kernel: K(d) = (exp(-s d^2) - exp(-s)) / (1 - exp(-s))
// for d < 1, else 0; SPLAT_SHARPNESS (s) is injected from Python.  Output is
// premultiplied (colour K, alpha K) for glBlendFunc(GL_ONE, GL_ONE_MINUS_SRC_ALPHA).
// With COUNT_FRAGMENTS defined every fragment the kernel keeps writes 1, for
// additive blending into the overdraw counter.

in vec2 splat_position;
flat in vec4 particle;
out vec4 frag_colour;

void main()
{
    float d2 = dot(splat_position, splat_position);
    if (d2 >= 1.0)
        discard;
#ifdef COUNT_FRAGMENTS
    frag_colour = vec4(1.0);
#else
    float floor_value = exp(-SPLAT_SHARPNESS);
    float kernel = (exp(-SPLAT_SHARPNESS * d2) - floor_value) / (1.0 - floor_value);
    frag_colour = particle * max(kernel, 0.0);
#endif
}

#version 330 core
// A particle's optical depth into the clouds' transmittance map, blended additively: -ln(1 - b K) at this texel,
// times the share of its slab in front of each slice's depth (cloudcore/light/cloud_shadows.py's _deposits; the
// last slice holds it whole).

in vec2 offset;
flat in float opacity;
flat in float scale;
flat in float slice_centre;
flat in float slice_half;

layout(location = 0) out vec4 slices_1_to_4;
layout(location = 1) out vec4 slices_5_to_8;

const float MOST_OPACITY = 1.0 - 1e-6;  // cloud_shadows.py's _MOST_OPACITY

float splat_kernel(float d)
{
    // cloudcore/maths/splat_kernel.py
    float floor_value = exp(-SPLAT_SHARPNESS);
    float k = (exp(-SPLAT_SHARPNESS * d * d) - floor_value) / (1.0 - floor_value);
    return d < 1.0 ? max(k, 0.0) : 0.0;
}

vec4 shares(vec4 slices)
{
    return clamp((slices - slice_centre + slice_half) / (2.0 * slice_half), 0.0, 1.0);
}

void main()
{
#ifdef POINTS
    float kernel = splat_kernel(length(gl_PointCoord * 2.0 - 1.0));
#else
    float kernel = splat_kernel(length(offset));
#endif
    if (kernel <= 0.0)
        discard;
    float optical_depth = -log(1.0 - min(opacity * kernel, MOST_OPACITY)) * scale;
    slices_1_to_4 = optical_depth * shares(vec4(1.0, 2.0, 3.0, 4.0));
    vec4 far = shares(vec4(5.0, 6.0, 7.0, 8.0));
    far.w = 1.0;
    slices_5_to_8 = optical_depth * far;
}

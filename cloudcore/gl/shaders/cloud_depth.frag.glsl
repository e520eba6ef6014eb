#version 430 core
// The core of a particle's disc at its centre's depth (cloud_depth.vert.glsl's point): no colour.

void main()
{
    vec2 across = 2.0 * gl_PointCoord - 1.0;
    if (dot(across, across) >= 1.0)
        discard;
}

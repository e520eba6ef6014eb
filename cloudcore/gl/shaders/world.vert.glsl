#version 330 core
// One triangle that covers the screen, from gl_VertexID alone (no vertex buffer), at the window depth DEPTH
// places it (the sky at the far plane, where the depth test keeps it behind whatever is drawn).  With VIEW_RAY, each
// pixel's ray too: from a perspective projection's near plane to its far plane it is linear in ndc, so its
// vertices' interpolate to each pixel's exactly, where unprojecting it per pixel cost two matrices and two
// divisions a pixel.

#ifndef DEPTH
#define DEPTH 0.0
#endif

out vec2 ndc;
#if VIEW_RAY
uniform mat4 inverse_view_projection;
out vec3 view_ray;  // not normalised: its direction is the pixel's

vec3 unproject(float depth)
{
    vec4 world = inverse_view_projection * vec4(ndc, depth, 1.0);
    return world.xyz / world.w;
}
#endif

void main()
{
    ndc = vec2(gl_VertexID == 1 ? 3.0 : -1.0, gl_VertexID == 2 ? 3.0 : -1.0);
    gl_Position = vec4(ndc, DEPTH, 1.0);
#if VIEW_RAY
    view_ray = unproject(1.0) - unproject(-1.0);
#endif
}

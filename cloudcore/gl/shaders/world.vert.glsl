#version 330 core
// One triangle that covers the screen, from gl_VertexID alone (no vertex buffer), at the window depth DEPTH
// places it (the sky at the far plane, where the depth test keeps it behind whatever is drawn).

#ifndef DEPTH
#define DEPTH 0.0
#endif

out vec2 ndc;

void main()
{
    ndc = vec2(gl_VertexID == 1 ? 3.0 : -1.0, gl_VertexID == 2 ? 3.0 : -1.0);
    gl_Position = vec4(ndc, DEPTH, 1.0);
}

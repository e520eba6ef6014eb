#version 330 core
// A textured quad from four corners given as uniforms (no vertex buffer):
// impostors and ring panels in world space, screen impostors in clip space
// (with an identity view_projection).  Triangle-strip order: lower left,
// lower right, upper left, upper right, so uv = (id & 1, id >> 1), mapped into
// uv_rect (u0, v0, u1, v1): the part of the texture the corners cover.

uniform vec3 corners[4];
uniform vec4 uv_rect;
uniform mat4 view_projection;

out vec2 uv;

void main()
{
    uv = mix(uv_rect.xy, uv_rect.zw, vec2(gl_VertexID & 1, gl_VertexID >> 1));
    gl_Position = view_projection * vec4(corners[gl_VertexID], 1.0);
}

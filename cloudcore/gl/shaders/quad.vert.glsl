#version 330 core
// A textured quad from four corners (no vertex buffer): impostors and ring
// panels in world space, screen impostors in clip space (with an identity
// view_projection).  Triangle-strip order: lower left, lower right, upper
// left, upper right, so uv = (id & 1, id >> 1), mapped into uv_rect
// (u0, v0, u1, v1): the part of the texture the corners cover.  The corners
// and uv_rect are uniforms, one quad a draw; with ATLAS they come per
// instance, a run of impostors from the atlas (cloudcore.gl.impostor_atlas)
// one draw, with the rectangle of its cell to clamp to and its layer.  AIR: world-space
// quads seen through the air from where the eye is now (quad.frag.glsl).

#ifdef ATLAS
layout(location = 0) in vec3 corner_0;
layout(location = 1) in vec3 corner_1;
layout(location = 2) in vec3 corner_2;
layout(location = 3) in vec3 corner_3;
layout(location = 4) in vec4 instance_uv_rect;
layout(location = 5) in vec4 instance_clamp_rect;
layout(location = 6) in vec2 instance_weight_layer;
flat out vec4 clamp_rect;
flat out vec2 weight_layer;
#else
uniform vec3 corners[4];
uniform vec4 uv_rect;
#endif
uniform mat4 view_projection;
#ifdef AIR
uniform vec3 eye_position;
out vec3 from_eye;  // the quad's point less the eye: the air between them, read in quad.frag.glsl
#endif

out vec2 uv;

void main()
{
#ifdef ATLAS
    vec3 corners[4] = vec3[4](corner_0, corner_1, corner_2, corner_3);
    vec4 uv_rect = instance_uv_rect;
    clamp_rect = instance_clamp_rect;
    weight_layer = instance_weight_layer;
#endif
    uv = mix(uv_rect.xy, uv_rect.zw, vec2(gl_VertexID & 1, gl_VertexID >> 1));
    gl_Position = view_projection * vec4(corners[gl_VertexID], 1.0);
#ifdef AIR
    from_eye = corners[gl_VertexID] - eye_position;
#endif
}

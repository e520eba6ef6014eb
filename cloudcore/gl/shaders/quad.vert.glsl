#version 420 core
// A textured quad from four corners (no vertex buffer): impostors and ring
// panels in world space, screen impostors in clip space (with an identity
// view_projection).  Triangle-strip order: lower left, lower right, upper
// left, upper right, so uv = (id & 1, id >> 1), mapped into uv_rect
// (u0, v0, u1, v1): the part of the texture the corners cover.  The corners
// and uv_rect are uniforms, one quad a draw; with ATLAS they come per
// instance, a run of impostors from the atlas (cloudcore.gl.impostor_atlas)
// one draw, with the rectangle of its cell to clamp to and its layer.  AIR: world-space
// quads seen through the air from where the eye is now, read at the corners of air_cells x air_cells
// cells cut from the quad (6 vertices a cell, as triangles) and interpolated: a wide quad's corners are
// farther than its middle, so a near one takes more cells (cloudcore.light.air_between.air_cells); with
// LIGHT_SHAFTS, less the light shafts' share of it (light_shafts_read.glsl).  PANEL_DEPTH: a ring panel, its
// world point passed on for quad.frag.glsl to put each fragment at its clouds' depth.

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
#include "aerial_perspective.glsl"
uniform vec3 eye_position;
uniform int air_cells;
out vec3 air_transmittance_at;  // the air between the eye and the vertex, applied in quad.frag.glsl
out vec3 air_in_scattered_at;
#ifdef LIGHT_SHAFTS
#include "light_shafts_read.glsl"
#endif
// a cell's two triangles, as (column, row) steps from its lower left corner
const vec2 CELL_CORNERS[6] = vec2[6](vec2(0, 0), vec2(1, 0), vec2(0, 1), vec2(0, 1), vec2(1, 0), vec2(1, 1));
#endif

out vec2 uv;
#ifdef PANEL_DEPTH
out vec3 panel_point;
#endif

void main()
{
#ifdef ATLAS
    vec3 corners[4] = vec3[4](corner_0, corner_1, corner_2, corner_3);
    vec4 uv_rect = instance_uv_rect;
    clamp_rect = instance_clamp_rect;
    weight_layer = instance_weight_layer;
#endif
#ifdef AIR
    int cell = gl_VertexID / 6;
    vec2 along = (vec2(cell % air_cells, cell / air_cells) + CELL_CORNERS[gl_VertexID % 6]) / float(air_cells);
    vec3 point = mix(mix(corners[0], corners[1], along.x), mix(corners[2], corners[3], along.x), along.y);
    air_toward(point - eye_position, air_transmittance_at, air_in_scattered_at);
#else
    vec2 along = vec2(gl_VertexID & 1, gl_VertexID >> 1);
    vec3 point = corners[gl_VertexID];
#endif
    uv = mix(uv_rect.xy, uv_rect.zw, along);
#ifdef PANEL_DEPTH
    panel_point = point;
#endif
    gl_Position = view_projection * vec4(point, 1.0);
#if defined(AIR) && defined(LIGHT_SHAFTS)
    // Yusov's cut: less the share of that air the clouds' shadows keep from the eye (marched up to the clouds'
    // nearest distance), read where the vertex falls on the screen, as the splats' and the terrain's
    if (gl_Position.w > 0.0)
        air_in_scattered_at *= 1.0 - light_shafts_at(clamp(gl_Position.xy / gl_Position.w, -1.0, 1.0)).a;
#endif
}

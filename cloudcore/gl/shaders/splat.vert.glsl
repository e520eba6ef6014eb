#version 430 core
#ifdef CELLS
#extension GL_ARB_shader_viewport_layer_array : require
#extension GL_ARB_shader_draw_parameters : require
#endif
// Draws the quads splat_shade.comp.glsl built: four vertices per particle,
// as indexed triangles rather than instances (a software rasteriser runs its
// vertex pipeline once per instance).  Corners come relative to the eye,
// so the view matrix applies without its translation.  With POINT_SPRITE
// defined, one vertex per particle instead, a point sprite of the quad's
// square (cloudcore.particles.point_sprites says when the picture is the same); its
// centre and radius come back from the corners, so that one compute shader
// serves both ways of drawing.  With CELLS defined, the points or quads of many
// impostors at once, one multi-draw's draw each: its cell's view, projection,
// viewport and atlas layer come from a table (a frame's regenerations into the
// atlas in one call; the viewports and scissors are the cells', set per index).
// With PIXEL_LOOK defined (per-pixel shading or detail noise: cloudcore.light.splat_look), it hands
// splat.frag.glsl the particle's sphere, its splat's plane and its pixel terms.

struct Instance {
    vec4 corners[4];  // relative to the eye; w: atlas cell (-1: Gaussian splat)
    vec4 colours[4];  // premultiplied linear rgb, opacity
};
layout(std430, binding = 3) readonly buffer Instances { Instance instances[]; };

uniform mat4 view_rotation;  // the view matrix without its translation
uniform mat4 projection;

out vec4 colour;          // per corner: the artist model's varies up a sprite
flat out int sprite;      // atlas cell, -1 for a Gaussian splat

#ifdef PIXEL_LOOK
struct PixelTerms {
    vec4 sun;    // the sun's part of the colour (rgb); w: the optical depth the sun's light falls by across it
    vec4 light;  // toward the sun; w: the particle's index
};
layout(std430, binding = 9) readonly buffer Terms { PixelTerms terms[]; };
flat out vec4 sphere;       // the particle's centre relative to the eye, its radius
flat out vec3 plane_right;  // the splat's axes, a radius long each: corners are centre -+ right -+ up
flat out vec3 plane_up;
flat out vec4 sun_part;
flat out vec4 sun_light;

// the particle's sphere and splat plane from its instance's corners, and its terms
void hand_on_look(Instance instance, int slot)
{
    plane_right = 0.5 * (instance.corners[1].xyz - instance.corners[0].xyz);
    plane_up = 0.5 * (instance.corners[2].xyz - instance.corners[0].xyz);
    sphere = vec4(0.5 * (instance.corners[0].xyz + instance.corners[3].xyz), length(plane_right));
    sun_part = terms[slot].sun;
    sun_light = terms[slot].light;
}
#endif

#ifdef CELLS
struct Cell {
    mat4 view_rotation;
    mat4 projection;
    vec4 viewport_height_layer;  // the cell's (points: guard-banded) viewport height in pixels, its atlas layer
};
layout(std430, binding = 8) readonly buffer Cells { Cell cells[]; };
uniform int first_cell;  // the cell of the multi-draw's first draw
#endif

#ifdef POINT_SPRITE
uniform float viewport_height;  // pixels

void main()
{
#ifdef CELLS
    Cell cell = cells[first_cell + gl_DrawIDARB];
    mat4 rotation = cell.view_rotation, clip = cell.projection;
    float height = cell.viewport_height_layer.x;
    gl_ViewportIndex = gl_DrawIDARB;
    gl_Layer = int(cell.viewport_height_layer.y);
#else
    mat4 rotation = view_rotation, clip = projection;
    float height = viewport_height;
#endif
    Instance instance = instances[gl_VertexID];
    // corners 0 and 3 are opposite, (-1, -1) and (1, 1); 0 and 1 are 2r apart along the image's right
    vec3 centre = 0.5 * (instance.corners[0].xyz + instance.corners[3].xyz);
    float radius = 0.5 * length(instance.corners[1].xyz - instance.corners[0].xyz);
    gl_Position = clip * (rotation * vec4(centre, 1.0));
    // the square's side in pixels: 2r * projection[1][1] / w of the 2 that the viewport's height spans
    gl_PointSize = radius * clip[1][1] * height / gl_Position.w;
    colour = instance.colours[0];
    sprite = -1;
#ifdef PIXEL_LOOK
    hand_on_look(instance, gl_VertexID);
#endif
}
#else
out vec2 splat_position;  // corner in radii: the kernel's d = length(splat_position)

const vec2 CORNERS[4] = vec2[](vec2(-1.0, -1.0), vec2(1.0, -1.0), vec2(-1.0, 1.0), vec2(1.0, 1.0));

void main()
{
    int slot = gl_VertexID >> 2, k = gl_VertexID & 3;
    vec4 corner = instances[slot].corners[k];
#ifdef CELLS
    Cell cell = cells[first_cell + gl_DrawIDARB];
    gl_Position = cell.projection * (cell.view_rotation * vec4(corner.xyz, 1.0));
    gl_ViewportIndex = gl_DrawIDARB;
    gl_Layer = int(cell.viewport_height_layer.y);
#else
    gl_Position = projection * (view_rotation * vec4(corner.xyz, 1.0));
#endif
    splat_position = CORNERS[k];
    colour = instances[slot].colours[k];
    sprite = int(corner.w);
#ifdef PIXEL_LOOK
    hand_on_look(instances[slot], slot);
#endif
}
#endif

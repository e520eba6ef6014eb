#version 430 core
// Draws the splats splat_shade.comp.glsl built as point sprites, one vertex
// per particle instead of four (cloudcore.point_sprites says when the picture
// is the same).  The centre and radius come back from the quad's corners:
// the compute shader stays one for both ways of drawing.

struct Instance {
    vec4 corners[4];  // relative to the eye; w: atlas cell (-1: Gaussian splat)
    vec4 colours[4];  // premultiplied linear rgb, opacity
};
layout(std430, binding = 3) readonly buffer Instances { Instance instances[]; };

uniform mat4 view_rotation;  // the view matrix without its translation
uniform mat4 projection;
uniform float viewport_height;  // pixels

out vec4 colour;
flat out int sprite;

void main()
{
    Instance instance = instances[gl_VertexID];
    // corners 0 and 3 are opposite (-1, -1) and (1, 1); 0 and 1 are 2r apart along the image's right
    vec3 centre = 0.5 * (instance.corners[0].xyz + instance.corners[3].xyz);
    float radius = 0.5 * length(instance.corners[1].xyz - instance.corners[0].xyz);
    gl_Position = projection * (view_rotation * vec4(centre, 1.0));
    // the square's side in pixels: 2r * projection[1][1] / w of the 2 that viewport_height spans
    gl_PointSize = radius * projection[1][1] * viewport_height / gl_Position.w;
    colour = instance.colours[0];
    sprite = -1;
}

#version 420 core
// The terrain's colour in linear RGB, seen through the air its vertices read (terrain.vert.glsl).

in vec3 sun_lit;
in vec3 sky_lit;
in vec3 air_let_through;
in vec3 air_added;
out vec4 frag_colour;

void main()
{
    frag_colour = vec4((sun_lit + sky_lit) * air_let_through + air_added, 1.0);
}

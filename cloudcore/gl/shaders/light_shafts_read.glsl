// The light shafts (light_shafts.frag.glsl's target, a fraction of the screen's resolution, seeing the same view)
// read bilinearly: the air's light the clouds' shadow takes, which the sky takes off its own, and its share of all
// the air's, by which the terrain scales its air's light.  A share, as what the terrain's air loses: between
// shaft pixels that saw different distances (a hill against the sky) the light taken changes, its share little.
// Unit 7: cloudcore.gl.light_shafts.SHAFTS_UNIT.
layout(binding = 7) uniform sampler2D light_shafts;

// (light taken, its share) at `ndc`, the point's place over the view (x, y each from -1 to 1); textureLod, as a
// vertex shader has no derivatives to choose a level by
vec4 light_shafts_at(vec2 ndc)
{
    return textureLod(light_shafts, 0.5 * ndc + 0.5, 0.0);
}

#version 430 core
// A Gaussian splat: the kernel of cloudcore.maths.splat_kernel, K(d) = (exp(-s d^2) - exp(-s)) / (1 - exp(-s))
// for d < 1, else 0, SPLAT_SHARPNESS (s) injected from Python.  Or an atlas sprite
// (cloudcore.artist.sprites): its cell's texture, alpha the sprite's opacity and rgb a
// brightness that multiplies the colour; only the ATLAS_SPRITES variant has that
// path (a batch without sprites would pay for its texture fetch, as a branch on a
// flat input still runs both ways on llvmpipe).  Output is premultiplied for
// glBlendFunc(GL_ONE, GL_ONE_MINUS_SRC_ALPHA).  With COUNT_FRAGMENTS defined every
// fragment kept writes 1, for additive blending into the overdraw counter.  With POINT_SPRITE
// defined it draws the point sprites of splat.vert.glsl.

#ifdef POINT_SPRITE
// a point's square, y up as the quad's (gl_PointCoord has its origin at the upper left)
#define splat_position vec2(2.0 * gl_PointCoord.x - 1.0, 1.0 - 2.0 * gl_PointCoord.y)
#else
in vec2 splat_position;
#endif
in vec4 colour;
flat in int sprite;
out vec4 frag_colour;

uniform sampler2D atlas;

void main()
{
    vec4 shade;
#ifdef ATLAS_SPRITES
    if (sprite < 0) {
#endif
        float d2 = dot(splat_position, splat_position);
        if (d2 >= 1.0)
            discard;
        float floor_value = exp(-SPLAT_SHARPNESS);
        shade = vec4(max((exp(-SPLAT_SHARPNESS * d2) - floor_value) / (1.0 - floor_value), 0.0));
#ifdef ATLAS_SPRITES
    } else {
        // cells are ATLAS_GRID wide, row 0 at the top (v = 0); the sprite's bottom edge is its cell's
        vec2 cell = vec2(sprite % ATLAS_GRID, sprite / ATLAS_GRID);
        vec2 uv = (cell + vec2(0.5 + 0.5 * splat_position.x, 0.5 - 0.5 * splat_position.y)) / float(ATLAS_GRID);
        vec4 texel = texture(atlas, uv);
        if (texel.a <= 0.0)
            discard;
        shade = vec4(texel.rgb * texel.a, texel.a);
    }
#endif
#ifdef COUNT_FRAGMENTS
    frag_colour = vec4(1.0);
#else
    frag_colour = colour * shade;
#endif
}

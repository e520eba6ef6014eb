#version 430 core
// A Gaussian splat: the kernel of cloudcore.maths.splat_kernel, K(d) = (exp(-s d^2) - exp(-s)) / (1 - exp(-s))
// for d < 1, else 0, SPLAT_SHARPNESS (s) injected from Python.  Or an atlas sprite
// (cloudcore.artist.sprites): its cell's texture, alpha the sprite's opacity and rgb a
// brightness that multiplies the colour; only the ATLAS_SPRITES variant has that
// path (a batch without sprites would pay for its texture fetch, as a branch on a
// flat input still runs both ways on llvmpipe).  Output is premultiplied for
// glBlendFunc(GL_ONE, GL_ONE_MINUS_SRC_ALPHA).  With COUNT_FRAGMENTS defined every
// fragment kept writes 1, for additive blending into the overdraw counter.  With POINT_SPRITE
// defined it draws the point sprites of splat.vert.glsl.  With PIXEL_LOOK defined, a Gaussian splat is shaded
// per pixel (PER_PIXEL: by the view ray's chord through the particle's sphere) or its optical depth varied by
// 3D noise (DETAIL_NOISE), or both: cloudcore.light.splat_look is the reference.

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

#ifdef PIXEL_LOOK
flat in vec4 sphere;       // the particle's centre relative to the eye, its radius
flat in vec3 plane_right;  // the splat's axes, a radius long each
flat in vec3 plane_up;
flat in vec4 sun_part;     // the sun's part of the colour (rgb); w: the optical depth the sun's light falls by across it
flat in vec4 sun_light;    // toward the sun; w: the particle's index
uniform float detail_amplitude;
uniform float detail_scale;  // metres between the noise's lattice points

// erf by Abramowitz and Stegun 7.1.26, |error| < 1.5e-7
float erf_approx(float x)
{
    float t = 1.0 / (1.0 + 0.3275911 * abs(x));
    float poly = ((((1.061405429 * t - 1.453152027) * t + 1.421413741) * t - 0.284496736) * t + 0.254829592) * t;
    return sign(x) * (1.0 - poly * exp(-x * x));
}

// cloudcore.maths.splat_kernel.kernel_ray_integral: K's integral from `start` (radii, inside the sphere) to
// the sphere's surface along unit `direction`
float kernel_ray_integral(vec3 start, vec3 direction)
{
    float along = dot(start, direction);
    float q2 = clamp(dot(start, start) - along * along, 0.0, 1.0);
    float half_chord = sqrt(1.0 - q2);
    float root = sqrt(SPLAT_SHARPNESS), floor_value = exp(-SPLAT_SHARPNESS);
    float gaussian = 0.8862269255 / root * exp(-SPLAT_SHARPNESS * q2)
                   * (erf_approx(root * half_chord) - erf_approx(root * along));
    return max((gaussian - (half_chord - along) * floor_value) / (1.0 - floor_value), 0.0);
}

// a lattice point's value in [0, 1]: an integer hash, the same on every GL
float lattice(ivec3 corner)
{
    uvec3 u = uvec3(corner) * uvec3(1597334673u, 3812015801u, 2798796415u);
    uint n = (u.x ^ u.y ^ u.z) * 1597334673u;
    n ^= n >> 16;
    return float(n) * (1.0 / 4294967295.0);
}

// value noise in [0, 1], smooth between lattice points a unit apart
float value_noise(vec3 x)
{
    vec3 base = floor(x), f = x - base, w = f * f * (3.0 - 2.0 * f);
    ivec3 c = ivec3(base);
    float low = mix(mix(lattice(c), lattice(c + ivec3(1, 0, 0)), w.x),
                    mix(lattice(c + ivec3(0, 1, 0)), lattice(c + ivec3(1, 1, 0)), w.x), w.y);
    float high = mix(mix(lattice(c + ivec3(0, 0, 1)), lattice(c + ivec3(1, 0, 1)), w.x),
                     mix(lattice(c + ivec3(0, 1, 1)), lattice(c + ivec3(1, 1, 1)), w.x), w.y);
    return mix(low, high, w.z);
}

// the pixel of a Gaussian splat whose kernel is `kernel` at `position` (radii in its plane), premultiplied
vec4 pixel_look(vec2 position, float kernel)
{
    vec3 centre = sphere.xyz;
    vec3 ray = normalize(centre + position.x * plane_right + position.y * plane_up);
    vec3 middle = (ray * dot(centre, ray) - centre) / max(sphere.w, 1e-30);  // the chord's middle, in radii
#ifdef PER_PIXEL
    vec4 base = colour;
    // the chord's optical depth over the diameter's: twice its half from the middle on (kernel_chord_integral)
    float share = 2.0 * kernel_ray_integral(middle, ray) / KERNEL_DIAMETER_INTEGRAL;
    float sun_depth = kernel_ray_integral(middle, sun_light.xyz) - 0.5 * KERNEL_DIAMETER_INTEGRAL;
    base.rgb += sun_part.rgb * (exp(-sun_part.w * sun_depth / KERNEL_DIAMETER_INTEGRAL) - 1.0);
#else
    vec4 base = colour * kernel;
    float share = 1.0;
#endif
#ifdef DETAIL_NOISE
    vec3 at = middle * (sphere.w / max(detail_scale, 1e-30))
            + 64.0 * fract(sun_light.w * vec3(0.7548776662, 0.5698402910, 0.3819660113));
    float n = (2.0 * value_noise(at) + value_noise(2.03 * at + 17.0)) / 3.0;
    share *= max(1.0 + detail_amplitude * (2.0 * n - 1.0), 0.0);
#endif
    float seen = 1.0 - exp(share * log(max(1.0 - base.a, 1.0 - MAX_OPACITY)));
    return vec4(max(base.rgb, 0.0) * (seen / max(base.a, 1e-30)), seen);
}
#endif

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
#ifdef PIXEL_LOOK
    if (sprite < 0)
        frag_colour = pixel_look(splat_position, shade.a);
#endif
#endif
}

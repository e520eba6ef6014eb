"""Yusov's volume-aware blending of particles (HPG 2014, section 5.5, eq. 10-17), its ray-marched check.

Each splat is composited as a volume instead of a billboard.  The mapping (one per pixel ray and
particle, so that a lone particle looks exactly as its splat does):

- the ray hits the splat's plane (through the centre, spanned by the view's right and up axes) at
  distance d from the centre, in radii, as `splat.frag.glsl` measures it; the splat draws opacity
  a = alpha K(d) and premultiplied colour c K(d) (`cloudcore.maths.splat_kernel`, `ParticleBuffer.seen_from`);
- the particle is a sphere of that radius, homogeneous along the ray: the segment is the chord
  [t_c - h, t_c + h] around the ray's closest approach t_c to the centre, h = r sqrt(1 - d^2);
- its optical depth tau = -ln(1 - a) (capped at `MAX_OPTICAL_DEPTH`), so its transmittance is the
  splat's 1 - a, and its density tau / 2h; its colour (not premultiplied) is c / alpha, so its
  premultiplied colour C (1 - T) is the splat's c K(d).

Along one ray, segments overlap: `volume_blend` composites them as Yusov's pixel-shader-ordering pass
does, particle by particle far to near, keeping per pixel one homogeneous volume (colour, density,
extent) closest to the eye: a segment that misses it sends the farther of the two into the frame; one
that overlaps it is split with it into back (eq. 12-13), intersection (eq. 14-15) and front (eq.
10-11).  Yusov sends the back part into the frame and holds front and intersection merged as one
homogeneous volume; here the intersection goes into the frame too and the front part alone is held.
Two particles come out the same (eq. 16-17 either way); with many, a merged volume spreads the colour
of the particles deep in it over its whole extent, toward the eye, and each merge spreads it further:
on the default view's cumulus (thousands of splats a tile) that was four times plain blending's error
against the ray march, where holding the front is below plain's (docs/shading.md).

`plain_blend` is what premultiplied billboards give, and `ray_marched` integrates the same densities
and colours in fine steps: the reference both are measured against.  The opaque world cuts segments
at its depth (a billboard is kept or not at its plane).

Images here are flat (pixels, 4) premultiplied linear RGBA over what the target held, alpha = 1 - T.
The GL twin is `cloudcore/gl/shaders/volume_blend.comp.glsl` (`cloudcore.gl.volume_blending`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cloudcore.maths.splat_kernel import splat_kernel
from cloudcore.model.settings import BLENDINGS

#: optical depth a segment is capped at: e^-50 of light gets through, nothing a 16-bit target holds,
#: and tau stays finite where a splat's opacity rounds to 1 (-ln 0)
MAX_OPTICAL_DEPTH = 50.0
#: what a pixel lets through of what lies behind it when the compute pass of plain splats stops walking its
#: splats near to far: what it leaves out is at most this much of the brightest radiance behind (the frame is
#: clamped to 1 before sRGB), under a fifth of an 8-bit level where sRGB's curve is steepest (12.92 x 255 /
#: 16384).  1/4096 took no less time on llvmpipe (docs/performance.md, "Compositing by compute")
FINISHED_TRANSMITTANCE = 1.0 / 16384
_TINY = np.finfo(np.float64).tiny


@dataclass(frozen=True)
class Splats:
    """Particles of one draw, far to near, relative to the eye: what the splats draw.

    `colours` (n, 3) premultiplied and `opacities` (n,) as `ParticleBuffer.seen_from` gives them;
    `right` and `up` the view's axes, the plane every splat lies in."""

    centres: np.ndarray  # (n, 3) minus the eye
    radii: np.ndarray
    colours: np.ndarray
    opacities: np.ndarray
    right: np.ndarray
    up: np.ndarray

    def __len__(self) -> int:
        return len(self.radii)

    def taken(self, positions: np.ndarray) -> Splats:
        """The splats at `positions`, in that order."""
        return Splats(
            self.centres[positions],
            self.radii[positions],
            self.colours[positions],
            self.opacities[positions],
            self.right,
            self.up,
        )


@dataclass(frozen=True)
class Segments:
    """One particle's segments along many rays: where it is along each, how thick, what colour."""

    near: np.ndarray  # (pixels,) ray distance where the chord starts
    far: np.ndarray  # and ends (near == far where the ray misses or grazes)
    plane: np.ndarray  # ray distance to the splat's plane: where a billboard is depth tested
    optical_depth: np.ndarray  # (pixels,) along the whole chord, 0 where the ray misses
    colour: np.ndarray  # (3,) not premultiplied


def particle_segments(splats: Splats, index: int, rays: np.ndarray) -> Segments:
    """The segments of particle `index` along unit `rays` (pixels, 3) from the eye (the mapping above).

    A particle of radius 0 has no chord and draws nothing, as its degenerate quad does."""
    centre, radius = splats.centres[index], float(splats.radii[index])
    normal = np.cross(splats.right, splats.up)
    facing = rays @ normal
    # a ray parallel to the plane (only beside the eye, where splats are faded out) never reaches it
    plane = np.where(np.abs(facing) > _TINY, (centre @ normal) / np.where(facing == 0.0, 1.0, facing), -1.0)
    offset = plane[:, None] * rays - centre
    reach = np.hypot(offset @ splats.right, offset @ splats.up)
    # d in radii, 1 (nothing drawn) past the edge, behind the eye or for a particle of no size
    d = np.divide(reach, radius, out=np.ones(len(rays)), where=(plane > 0.0) & (reach < radius))
    alpha = float(splats.opacities[index])
    opacity = np.minimum(alpha * splat_kernel(d), 1.0)
    half = radius * np.sqrt(np.maximum(1.0 - d * d, 0.0))
    optical_depth = np.where(half > 0.0, np.minimum(-np.log1p(-opacity), MAX_OPTICAL_DEPTH), 0.0)
    closest = rays @ centre
    colour = splats.colours[index] / alpha if alpha > 0.0 else np.zeros(3)
    return Segments(closest - half, closest + half, plane, optical_depth, colour)


def _over(image: np.ndarray, where, colour: np.ndarray, transmittance: np.ndarray) -> None:
    """image = premultiplied (colour, 1 - transmittance) over image at the pixels `where`, in place."""
    image[where, :3] = colour[where] + transmittance[where, None] * image[where, :3]
    image[where, 3] = (1.0 - transmittance[where]) + transmittance[where] * image[where, 3]


def _homogeneous(colour: np.ndarray, optical_depth: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(premultiplied colour, transmittance) of a homogeneous segment: eq. 10-13, C (1 - e^-tau)."""
    transmittance = np.exp(-optical_depth)
    return colour * (1.0 - transmittance)[:, None], transmittance


def plain_blend(splats: Splats, rays: np.ndarray, background: np.ndarray, opaque: np.ndarray | None = None):
    """Billboards: ONE, ONE_MINUS_SRC_ALPHA far to near, each kept where its plane is nearer than
    `opaque` (ray distance to the world, inf: none).  Returns (pixels, 4)."""
    image = np.array(background, dtype=np.float64)
    opaque = np.full(len(rays), np.inf) if opaque is None else opaque
    everywhere = np.ones(len(rays), dtype=bool)
    for index in range(len(splats)):
        segments = particle_segments(splats, index, rays)
        optical_depth = np.where(segments.plane < opaque, segments.optical_depth, 0.0)
        _over(image, everywhere, *_homogeneous(np.broadcast_to(segments.colour, (len(rays), 3)), optical_depth))
    return image


def _cut(segments: Segments, opaque: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(near, far, optical depth) of the segments cut where the world is: the part behind it is gone."""
    far = np.clip(opaque, segments.near, segments.far)
    kept = (far - segments.near) / np.maximum(segments.far - segments.near, _TINY)
    return segments.near, far, segments.optical_depth * kept


#: what `volume_blend` holds of two overlapping segments: "front" (built, on the GL too), or Yusov's
#: "merged" front and intersection (the paper's, kept here to measure the difference: docs/shading.md)
HOLDS = ("front", "merged")


def volume_blend(
    splats: Splats, rays: np.ndarray, background: np.ndarray, opaque: np.ndarray | None = None, hold: str = "front"
):
    """Volume-aware blending (Yusov, section 5.5), far to near; returns (pixels, 4) premultiplied."""
    if hold not in HOLDS:
        raise ValueError(f"hold must be one of {', '.join(HOLDS)}, got {hold!r}")
    image = np.array(background, dtype=np.float64)
    pixels = len(rays)
    opaque = np.full(pixels, np.inf) if opaque is None else opaque
    # per pixel the volume closest to the eye: extent, optical depth, colour (not premultiplied)
    held = (np.zeros(pixels), np.zeros(pixels), np.zeros(pixels), np.zeros((pixels, 3)))
    for index in range(len(splats)):
        segments = particle_segments(splats, index, rays)
        new = (*_cut(segments, opaque), np.broadcast_to(segments.colour, (pixels, 3)))
        near, far, depth, colour = held
        arrives, empty = new[2] > 0.0, depth <= 0.0
        apart = arrives & ~empty & ((new[0] >= far) | (new[1] <= near))
        # apart: the farther of the two goes into the frame, the nearer is held
        new_nearer = new[0] < near
        _over(image, apart & new_nearer, *_homogeneous(colour, depth))
        _over(image, apart & ~new_nearer, *_homogeneous(new[3], new[2]))
        replace = arrives & (empty | (apart & new_nearer))
        overlap = arrives & ~empty & ~apart
        front, intersection, back = _split(held, new)
        # overlapping: the back part, then the intersection, are behind all still to come here (eq. 16-17
        # are these "over"s); the front part is held, for the next particle to meet
        _over(image, overlap, *_homogeneous(back[3], back[2]))
        if hold == "front":
            _over(image, overlap, *_homogeneous(intersection[3], intersection[2]))
        else:
            front = _merged(front, intersection)
        for kept, arriving, part in zip(held, new, front):
            kept[replace] = arriving[replace]
            kept[overlap] = part[overlap]
    _over(image, held[2] > 0.0, *_homogeneous(held[3], held[2]))
    return image


def _split(first, second):
    """Two overlapping homogeneous segments, each (near, far, optical depth, colour) per pixel, in their
    three parts, each a segment the same way (eq. 10-15): the front, of the one that starts first; the
    intersection; the back, of the one that ends last."""
    near0, far0, depth0, colour0 = first
    near1, far1, depth1, colour1 = second
    density0 = depth0 / np.maximum(far0 - near0, _TINY)
    density1 = depth1 / np.maximum(far1 - near1, _TINY)
    front_start, front_end = np.minimum(near0, near1), np.maximum(near0, near1)
    back_start, back_end = np.minimum(far0, far1), np.maximum(far0, far1)
    starts_first = near0 <= near1
    ends_last = far0 >= far1
    # eq. 10-11: the front part, of the segment that starts first
    front_depth = np.where(starts_first, density0, density1) * (front_end - front_start)
    front = (front_start, front_end, front_depth, np.where(starts_first[:, None], colour0, colour1))
    # eq. 14-15: the intersection, densities adding, colours weighted by density
    inside_end = np.maximum(back_start, front_end)
    weight0 = (density0 / np.maximum(density0 + density1, _TINY))[:, None]
    inside_colour = weight0 * colour0 + (1.0 - weight0) * colour1
    intersection = (front_end, inside_end, (density0 + density1) * (inside_end - front_end), inside_colour)
    # eq. 12-13: the back part, of the segment that ends last
    back_depth = np.where(ends_last, density0, density1) * (back_end - back_start)
    back = (back_start, back_end, back_depth, np.where(ends_last[:, None], colour0, colour1))
    return front, intersection, back


def _merged(front, intersection):
    """Yusov's held volume: the front segment and the intersection behind it as one homogeneous
    segment of their joint extent, its transmittance and colour eq. 16-17's."""
    front_colour, front_t = _homogeneous(front[3], front[2])
    inside_colour, inside_t = _homogeneous(intersection[3], intersection[2])
    transmittance = front_t * inside_t
    colour = (front_colour + front_t[:, None] * inside_colour) / np.maximum(1.0 - transmittance, _TINY)[:, None]
    return front[0], intersection[1], front[2] + intersection[2], colour


def ray_marched(
    splats: Splats,
    rays: np.ndarray,
    background: np.ndarray,
    opaque: np.ndarray | None = None,
    steps: int = 1024,
    chunk: int = 4096,
):
    """The reference: every particle's density and colour along each ray summed into `steps` fine
    intervals (exact overlap lengths) between the pixel's nearest and farthest segment end, then the
    emission-absorption integral marched through them, `chunk` pixels at a time; returns (pixels, 4)."""
    opaque = np.full(len(rays), np.inf) if opaque is None else opaque
    image = np.array(background, dtype=np.float64)
    for first in range(0, len(rays), chunk):
        part = slice(first, first + chunk)
        image[part] = _march(splats, rays[part], image[part], opaque[part], steps)
    return image


def ray_marched_in_tiles(
    splats: Splats, rays: np.ndarray, background: np.ndarray, opaque: np.ndarray, tiles: ScreenTiles, steps: int
):
    """`ray_marched` of a whole frame (rays and images top row first, as `pixel_rays` gives them), each
    screen tile with only the splats `tiles` lists for it: the same picture, for many particles at a
    cost of the splats' pixels rather than particles times pixels."""
    image = np.array(background, dtype=np.float64)
    for tile in tiles.occupied:
        pixels = tile_pixels(tiles, int(tile))
        listed = tiles.entries[tiles.starts[tile] : tiles.starts[tile + 1]]
        image[pixels] = _march(splats.taken(listed), rays[pixels], image[pixels], opaque[pixels], steps)
    return image


def tile_pixels(tiles: ScreenTiles, tile: int) -> np.ndarray:
    """The flat indices, in an image whose top row is first, of the pixels of `tile` (on the screen)."""
    width, height = tiles.size
    across = tile % tiles.across
    columns = np.arange(TILE_PIXELS * across, min(TILE_PIXELS * (across + 1), width))
    up = tile // tiles.across
    rows = np.arange(TILE_PIXELS * up, min(TILE_PIXELS * (up + 1), height))
    return ((height - 1 - rows)[:, None] * width + columns[None, :]).ravel()  # GL counts rows up


def _march(splats: Splats, rays, image, opaque, steps: int):
    pixels = len(rays)
    cut = []
    for index in range(len(splats)):
        segments = particle_segments(splats, index, rays)
        cut.append((*_cut(segments, opaque), segments.colour))
    if not cut:
        return image
    start = np.min([np.where(c[2] > 0.0, c[0], np.inf) for c in cut], axis=0)
    stop = np.max([np.where(c[2] > 0.0, c[1], -np.inf) for c in cut], axis=0)
    hit = np.isfinite(start)
    start, stop = np.where(hit, start, 0.0), np.where(hit, stop, 0.0)
    edges = start[:, None] + ((stop - start) / steps)[:, None] * np.arange(steps + 1)
    optical = np.zeros((pixels, steps))
    emitted = np.zeros((pixels, steps, 3))
    for near, far, depth, colour in cut:
        rows = np.flatnonzero(depth > 0.0)
        if not len(rows):
            continue
        density = depth[rows] / np.maximum(far[rows] - near[rows], _TINY)
        inside = np.minimum(far[rows, None], edges[rows, 1:]) - np.maximum(near[rows, None], edges[rows, :-1])
        added = density[:, None] * np.maximum(inside, 0.0)
        optical[rows] += added
        emitted[rows] += added[..., None] * colour
    transmittance = np.exp(-optical)
    # each interval: the density-weighted colour of what is in it, times the light it stops
    colour_in = emitted / np.maximum(optical, _TINY)[..., None]
    ahead = np.concatenate([np.ones((pixels, 1)), np.cumprod(transmittance, axis=1)[:, :-1]], axis=1)
    cloud = np.sum((ahead * (1.0 - transmittance))[..., None] * colour_in, axis=1)
    total = np.prod(transmittance, axis=1)
    out = image.copy()
    out[:, :3] = cloud + total[:, None] * image[:, :3]
    out[:, 3] = (1.0 - total) + total * image[:, 3]
    return out


def blending_path(requested: str, *, compute_shaders: bool, plain_splats_only: bool) -> str:
    """How one full-3D batch is composited: "volume" (the tiled compute pass) where the setting asks for
    it, the GL has compute shaders and every particle is a plain Gaussian splat of one colour
    (`cloudcore.particles.point_sprites.plain_splats`: the pass draws no sprites nor per-corner colours); else
    "plain" billboards.  Where a GL has GL_ARB_fragment_shader_interlock, Yusov's own fragment-shader
    path would be a third answer here; none is written (this project has no GL to test one on)."""
    if requested not in BLENDINGS:
        raise ValueError(f"blending must be one of {', '.join(BLENDINGS)}, got {requested!r}")
    return "volume" if requested == "volume" and compute_shaders and plain_splats_only else "plain"


@dataclass(frozen=True)
class ScreenTiles:
    """Which particles of a batch can touch each screen tile: the compute pass's work, one group a tile.

    Tiles are `TILE_PIXELS` square, counted from the lower left as GL counts pixels; tile i's particles
    are `entries[starts[i]:starts[i + 1]]`, positions in the batch, in its far-to-near order."""

    size: tuple[int, int]
    across: int
    up: int
    starts: np.ndarray  # (across * up + 1,) uint32
    entries: np.ndarray  # uint32

    @property
    def count(self) -> int:
        return self.across * self.up

    @property
    def occupied(self) -> np.ndarray:
        """(k,) uint32: the tiles some splat may touch, the only ones the pass runs on (the others keep
        what the target holds)."""
        return np.flatnonzero(np.diff(self.starts) > 0).astype(np.uint32)


#: pixels on a side of the compute pass's tiles (its work groups).  Smaller tiles list fewer splats that
#: miss a pixel, more tiles per splat: on llvmpipe, default view at 320x240, the volume pass took 7.3
#: times plain with 8, 14.8 with 16, 8.2 with 4 (docs/shading.md, "Volume-aware blending")
TILE_PIXELS = 8


def screen_tiles(centres, radii, view: np.ndarray, projection: np.ndarray, size, near: float) -> ScreenTiles:
    """Bin a batch's splats (`centres` relative to the eye, far to near) into the screen's tiles.

    A splat lies in the image plane, so its image is the square (x +- r, y +- r) at its depth, projected,
    and its kernel's the disc inscribed in it; a tile holds the splat when the disc reaches one of its pixels'
    centres (one pixel of margin, for rounding): of the square's tiles, a quarter fewer on the default view.
    Splats not in front of the `near` plane are in no tile, as the rasteriser clips them."""
    width, height = int(size[0]), int(size[1])
    across, up = -(-width // TILE_PIXELS), -(-height // TILE_PIXELS)
    centres = np.asarray(centres, dtype=np.float64).reshape(-1, 3)
    radii = np.asarray(radii, dtype=np.float64)
    depth = centres @ -view[2, :3]
    ahead = depth > near
    safe_depth = np.where(ahead, depth, 1.0)
    columns = _pixel_span(centres @ view[0, :3], radii, safe_depth, projection[0, 0], width)
    rows = _pixel_span(centres @ view[1, :3], radii, safe_depth, projection[1, 1], height)
    seen = ahead & (columns[1] >= columns[0]) & (rows[1] >= rows[0])
    first_x, last_x = columns[0][seen] // TILE_PIXELS, columns[1][seen] // TILE_PIXELS
    first_y, last_y = rows[0][seen] // TILE_PIXELS, rows[1][seen] // TILE_PIXELS
    wide, tall = last_x - first_x + 1, last_y - first_y + 1
    positions = np.repeat(np.flatnonzero(seen), wide * tall)
    # the k-th tile of a splat's box, row by row
    local = np.arange(len(positions)) - np.repeat(np.cumsum(wide * tall) - wide * tall, wide * tall)
    box_wide = np.repeat(wide, wide * tall)
    row = np.repeat(first_y, wide * tall) + local // box_wide
    column = np.repeat(first_x, wide * tall) + local % box_wide
    # the disc, in pixels: its centre and radius (the wider of the square's sides, as the GPU's binning has it)
    disc_x = (centres[seen] @ view[0, :3]) * projection[0, 0] / safe_depth[seen]
    disc_y = (centres[seen] @ view[1, :3]) * projection[1, 1] / safe_depth[seen]
    centre_x = np.repeat((disc_x + 1.0) * 0.5 * width - 0.5, wide * tall)
    centre_y = np.repeat((disc_y + 1.0) * 0.5 * height - 0.5, wide * tall)
    scale = np.maximum(projection[0, 0] * width, projection[1, 1] * height) * 0.5
    reach = np.repeat(radii[seen] * scale / safe_depth[seen] + 1.0, wide * tall)
    nearest_x = np.clip(centre_x, column * TILE_PIXELS, column * TILE_PIXELS + TILE_PIXELS - 1)
    nearest_y = np.clip(centre_y, row * TILE_PIXELS, row * TILE_PIXELS + TILE_PIXELS - 1)
    reached = (nearest_x - centre_x) ** 2 + (nearest_y - centre_y) ** 2 <= reach**2
    positions, tile = positions[reached], (row * across + column)[reached]
    order = np.argsort(tile, kind="stable")  # stable: the batch's order within each tile
    starts = np.concatenate([[0], np.cumsum(np.bincount(tile, minlength=across * up))])
    return ScreenTiles((width, height), across, up, starts.astype(np.uint32), positions[order].astype(np.uint32))


def _pixel_span(along, radii, depth, focal, pixels: int) -> tuple[np.ndarray, np.ndarray]:
    """(first, last) pixel index, clipped to the screen, whose centres the spans along +- radii cover."""
    low = ((along - radii) * focal / depth + 1.0) * 0.5 * pixels - 0.5
    high = ((along + radii) * focal / depth + 1.0) * 0.5 * pixels - 0.5
    first = np.clip(np.floor(low) - 1.0, 0, pixels)
    last = np.clip(np.ceil(high) + 1.0, -1, pixels - 1)
    return first.astype(np.int64), last.astype(np.int64)


def ray_distances(window_depth: np.ndarray, rays: np.ndarray, view: np.ndarray, projection: np.ndarray) -> np.ndarray:
    """Distances along unit `rays` to the world, from a frame's window depths (the same pixels, flat);
    inf where the depth is cleared (1: nothing drawn).  The shader makes the same conversion."""
    window_depth = np.asarray(window_depth, dtype=np.float64).ravel()
    ndc = 2.0 * window_depth - 1.0
    eye_depth = projection[2, 3] / np.where(window_depth < 1.0, ndc + projection[2, 2], -1.0)
    return np.where(window_depth < 1.0, eye_depth / np.maximum(rays @ -view[2, :3], _TINY), np.inf)

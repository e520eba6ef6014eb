"""Harris multiple forward scattering: the light that reaches each particle.

Harris, "Real-Time Cloud Rendering for Games", GDC 2002, section 2.2.1, eq. 4,
and the illumination pass of figure 4: particles are visited in light order
(nearest the light first) over a light-plane "frame buffer" cleared to 1.  Each
particle reads the value at its own centre (its incident light I_k), then is
splatted with

    value = sigma_k * I_k * K_k(x) + (1 - alpha_k * K_k(x)) * value

where alpha_k = 1 - exp(-tau_k), sigma_k = a_k tau_k p(0) / (4 pi) and K is the
splat kernel (`cloudcore.maths.splat_kernel`).

Stability.  Where sigma_k > alpha_k (tau above about 9.3 at albedo 0.9 with
Rayleigh) the literal recurrence sends on more light than reached the particle.
We use sigma_eff = min(sigma_k, alpha_k): identical to the paper wherever it is
stable, continuous in tau, and it makes every blend a convex combination of the
old value and I_k <= 1, so all values stay in [0, 1].  An optically thick
particle then forward-scatters everything it stops, which is where the paper's
own trend (thicker particles pass on more) is heading.  The eye pass uses the
same cap (`scattering_coefficient`), with the phase function for the view.

Two methods:

* "exact": the frame buffer is sampled only at the particle centres, which is all
  that is ever read.  Each overlap (source j, later target i) is an affine map
  v -> A v + B on the value at i; affine maps compose associatively, so once all
  of a target's sources are known its value is a segmented scan over its
  sources in light order.  Targets become ready in dependency levels (Kahn's
  algorithm), so the Python loop runs over levels, not particles.
* "raster": Harris's frame buffer as a grid, walked in depth slabs; particles in
  one slab read the grid together and are splatted together with
  order-independent compositing.  Faster and approximate; see `docs/shading.md`.
* "preview": the raster method on a grid of `PREVIEW_RASTER_RESOLUTION` cells, in slabs of
  `PREVIEW_SLAB_FRACTION`: what the editor lights with while a lighting slider is dragged.
* "occlusion": not Harris's: Yusov's light-space occlusion estimate (`cloudcore.light.occlusion`), the
  sunlight through the other particles with no light order, each particle losing the share
  1 - sigma_eff / alpha of what it stops; the light pass of Yusov's model (eye pass "yusov").
* "octaves": not Harris's either: the exact method's overlaps, but each particle's light is the direct
  light plus Wrenninge's multiple-scattering octaves, transmittances toward the light through the particles
  ahead with their optical depths scaled, each counting only the light the direct beam has lost
  (`cloudcore.light.octaves`); no light order is needed.
* "octaves-lit-face": the octaves, each particle's light then increased by what the medium behind it (away
  from the light) reflects back to it (`cloudcore.light.lit_face`): one more product, over the overlaps behind each
  particle, which the same search finds.  That light arrives from every direction behind the particle, so
  `light_parts` gives it apart (`RETURNED_LIGHT`) for the eye pass to scatter with the phase function's mean.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from cloudcore.light.lit_face import lit_face_return
from cloudcore.light.occlusion import occlusion_estimate
from cloudcore.light.octaves import most_light, octave_light, octave_optical_depths
from cloudcore.light.phase import check_phase, phase_function
from cloudcore.light.precomputed import eye_pass_profiles
from cloudcore.maths.segments import concatenated_ranges
from cloudcore.maths.splat_kernel import splat_kernel

METHODS = ("exact", "raster", "preview", "occlusion", "octaves", "octaves-lit-face")
#: what a particle sends toward the eye (`cloudcore.particles.buffer`): Harris's eq. 5 as printed,
#: "saturated", its scattering coefficient and ambient term made those of a thick medium, or "yusov", the
#: light leaving Yusov's precomputed reference particle (`cloudcore.light.precomputed`)
EYE_PASSES = ("harris", "saturated", "yusov")
#: how the light reaching each particle is found (`[shading] light_pass`): Harris's multiple forward
#: scattering (computed by the method asked: exact, raster or the editor's preview) or Yusov's
#: light-space occlusion estimate (the method "occlusion" in place of exact and raster), or Wrenninge's
#: multiple-scattering octaves over Harris's light-plane overlaps (the method "octaves": `cloudcore.light.octaves`),
#: or the octaves with the light a cloud's lit face sends back (`cloudcore.light.lit_face`)
LIGHT_PASSES = ("harris", "occlusion", "octaves", "octaves-lit-face")
#: the light passes that send light back (`RETURNED_LIGHT`): the eye pass reads a second light column for them
RETURNING_LIGHT_PASSES = ("octaves-lit-face",)
FOUR_PI = 4.0 * np.pi
#: the columns of `light_parts`: all the light that reaches a particle, and the part of it the medium behind the
#: particle sends back (a cloud's lit face, `cloudcore.light.lit_face`; 0 in the other light passes), which
#: arrives from every direction behind it, so the eye pass scatters it with the phase function's mean (1) rather
#: than at the angle between the view and the light
ALL_LIGHT, RETURNED_LIGHT = 0, 1

#: raster grid cells across the widest axis of a cloud's light-plane footprint.
DEFAULT_RASTER_RESOLUTION = 48
#: the preview's grid: the default scene (sun and skylight) in 0.23 s against the default raster's 0.70 s
#: and exact's 1.88 s, a mean error of 0.065 in the fraction of light arriving against the default raster's
#: 0.025 (docs/shading.md)
PREVIEW_RASTER_RESOLUTION = 16
#: raster depth-slab thickness as a fraction of the cloud's median particle radius;
#: thin slabs cost little and remove most of the in-slab self-shadowing error
#: (docs/shading.md has the sweep).
DEFAULT_SLAB_FRACTION = 0.05
#: the preview's slabs, twice as thick: the preview's slab walk (a numpy step per slab) was most of its time once
#: its footprints were cut; its light's mean error 0.064 -> 0.073, its look's picture 0.3-0.5 dB further from the
#: exact look's, for about a quarter less time (docs/shading.md)
PREVIEW_SLAB_FRACTION = 0.1


def scattering_coefficient(optical_depth, albedo, phase: str = "rayleigh", g: float = 0.0) -> np.ndarray:
    """a tau / (4 pi), capped at alpha / p(0) so that no particle creates light.

    Multiply by p(cos_theta) for the scattering factor in any direction: forward
    (light pass) it gives sigma_eff = min(sigma, alpha); toward the eye (Harris
    eq. 5) it gives S_k / I_k.
    """
    tau = np.asarray(optical_depth, dtype=np.float64)
    alpha = -np.expm1(-tau)
    p_forward = float(phase_function(1.0, phase, g))
    return np.minimum(np.asarray(albedo, dtype=np.float64) * tau / FOUR_PI, alpha / p_forward)


def eye_pass_coefficients(
    optical_depth, albedo, phase: str = "rayleigh", g: float = 0.0, eye_pass: str = "harris"
) -> tuple[np.ndarray, np.ndarray]:
    """(scattering coefficient, ambient weight) per particle for the eye pass: colour = (sum over lights
    of I p(theta) radiance) * scattering + ambient * ambient weight.

    "harris": `scattering_coefficient` and the opacity alpha (Harris eq. 5).  "saturated": a (1 - e^-tau)
    / (4 pi) (with the same cap, alpha / p(0)), which is a tau / (4 pi) for thin particles but stops
    growing once a particle is opaque (light scattered once toward the eye comes from within about one
    optical depth of its surface: Harris's grows to 0.57 at tau 8, eight times what a thick medium of
    albedo 0.9 can send), and
    alpha times the reflectance of a thick medium (1 - s) / (1 + s), s = sqrt(1 - a) (two-stream; 1 at
    albedo 1, where Harris's ambient term is exact).  Against the path-traced truth of the default view
    at 160x120: 13.0 -> 23.6 dB at noon, 15.0 -> 24.0 dB at 18:15, at the same cost (docs/shading.md).

    "yusov": the opacity alpha, which multiplies the reference particle's light leaving toward the eye
    (its view-dependent profiles: `cloudcore.light.precomputed.eye_pass_profiles`, which stand in for
    the phase function), and alpha times the particle's response to uniform light.
    """
    if eye_pass not in EYE_PASSES:
        raise ValueError(f"unknown eye pass {eye_pass!r}; valid: {', '.join(EYE_PASSES)}")
    tau = np.asarray(optical_depth, dtype=np.float64)
    albedo = np.asarray(albedo, dtype=np.float64)
    alpha = -np.expm1(-tau)
    if eye_pass == "harris":
        return scattering_coefficient(tau, albedo, phase, g), alpha
    if eye_pass == "yusov":
        return alpha, alpha * eye_pass_profiles(tau, albedo, phase, g).ambient
    s = np.sqrt(1.0 - albedo)
    # the same cap as Harris's: no particle sends more light forward than it stops
    p_forward = float(phase_function(1.0, phase, g))
    return np.minimum(albedo * alpha / FOUR_PI, alpha / p_forward), alpha * (1.0 - s) / (1.0 + s)


def incident_light(positions, radii, optical_depth, albedo, light_dir, **options) -> np.ndarray:
    """Fraction of the light from `light_dir` that reaches each particle centre, float64 (N,): all of it (the
    column `ALL_LIGHT` of `light_parts`, which says what the arguments and keyword `options` are)."""
    return light_parts(positions, radii, optical_depth, albedo, light_dir, **options)[:, ALL_LIGHT]


def light_parts(
    positions,
    radii,
    optical_depth,
    albedo,
    light_dir,
    *,
    phase: str = "rayleigh",
    g: float = 0.0,
    method: str = "exact",
    groups=None,
    resolution: int = DEFAULT_RASTER_RESOLUTION,
) -> np.ndarray:
    """Fraction of the light from `light_dir` that reaches each particle centre, float64 (N, 2): all of it and
    the part the medium behind the particle sends back (the columns `ALL_LIGHT`, `RETURNED_LIGHT`).

    positions (N, 3); radii (N,); optical_depth (N,) = tau through the centre;
    albedo (N,) in [0, 1]; light_dir (3,) points from the scene toward the light.
    `groups` (N,) ints, optional: particles only shadow particles of their own
    group (Harris shades each cloud on its own), so many clouds shade in one call.
    Scalars broadcast for radii, optical_depth and albedo.
    """
    positions, radii, tau, albedo, light = _validated(positions, radii, optical_depth, albedo, light_dir)
    check_phase(phase, g)
    if method not in METHODS:
        raise ValueError(f"unknown shading method {method!r}; valid: {', '.join(METHODS)}")
    n = len(positions)
    if n == 0:
        return np.zeros((0, 2))
    groups = np.zeros(n, dtype=np.int64) if groups is None else np.asarray(groups).reshape(n)

    u, v = _light_plane_axes(light)
    plane = np.stack([positions @ u, positions @ v], axis=1)
    toward_light = positions @ light
    alpha = -np.expm1(-tau)
    sigma = scattering_coefficient(tau, albedo, phase, g) * float(phase_function(1.0, phase, g))
    if method in ("octaves", "octaves-lit-face"):
        octave_alpha = -np.expm1(-octave_optical_depths(tau))
        if method == "octaves":
            through = _transmittance_exact(plane, toward_light, radii, octave_alpha, groups)
            return _along_the_light(np.clip(octave_light(np.clip(through, 0.0, 1.0)), 0.0, most_light()))
        through, behind = _transmittance_exact(plane, toward_light, radii, octave_alpha, groups, behind=alpha[:, None])
        light = np.clip(octave_light(np.clip(through, 0.0, 1.0)), 0.0, most_light())
        # the optical thickness behind each particle (away from the light), as the product of 1 - alpha K there
        depth_behind = -np.log(np.clip(behind[:, 0], np.finfo(np.float64).tiny, 1.0))
        returned = light * lit_face_return(depth_behind, albedo, phase, g)
        return np.column_stack([light + returned, returned])
    if method == "exact":
        result = _incident_exact(plane, toward_light, radii, alpha, sigma, groups)
    elif method == "occlusion":
        lost = 1.0 - np.divide(sigma, alpha, out=np.zeros(n), where=alpha > 0.0)
        result = occlusion_estimate(plane, toward_light, radii, tau, lost, groups)
    else:
        grid, slabs = (
            (PREVIEW_RASTER_RESOLUTION, PREVIEW_SLAB_FRACTION)
            if method == "preview"
            else (int(resolution), DEFAULT_SLAB_FRACTION)
        )
        result = _incident_raster(plane, toward_light, radii, alpha, sigma, groups, grid, slabs)
    # Every step is a convex combination of values in [0, 1]; clip only rounding.
    return _along_the_light(np.clip(result, 0.0, 1.0))


def _along_the_light(light: np.ndarray) -> np.ndarray:
    """`light_parts` of a pass whose light (N,) all comes along the light's direction: none sent back."""
    return np.column_stack([light, np.zeros(len(light))])


def _validated(positions, radii, optical_depth, albedo, light_dir):
    positions = np.asarray(positions, dtype=np.float64)
    if positions.ndim != 2 or positions.shape[1] != 3:
        raise ValueError(f"positions must have shape (N, 3), got {positions.shape}")
    n = len(positions)

    def per_particle(name, value):
        array = np.asarray(value, dtype=np.float64)
        if array.ndim == 0:
            array = np.full(n, float(array))
        if array.shape != (n,):
            raise ValueError(f"{name} must have shape ({n},) or be a scalar, got {array.shape}")
        if not np.all(np.isfinite(array)):
            raise ValueError(f"{name} must be finite (found NaN or Inf)")
        return array

    radii = per_particle("radii", radii)
    tau = per_particle("optical_depth", optical_depth)
    albedo = per_particle("albedo", albedo)
    if not np.all(np.isfinite(positions)):
        raise ValueError("positions must be finite (found NaN or Inf)")
    if np.any(radii < 0):
        raise ValueError("radii must be >= 0")
    if np.any(tau < 0):
        raise ValueError("optical_depth must be >= 0")
    if np.any((albedo < 0) | (albedo > 1)):
        raise ValueError("albedo must be within [0, 1]")
    light = np.asarray(light_dir, dtype=np.float64)
    if light.shape != (3,) or not np.all(np.isfinite(light)):
        raise ValueError(f"light_dir must be a finite 3-vector, got {light_dir!r}")
    length = np.linalg.norm(light)
    if not length > 0:
        raise ValueError("light_dir must not be the zero vector")
    return positions, radii, tau, albedo, light / length


def _light_plane_axes(light: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Two unit vectors spanning the plane perpendicular to `light` (the light's view)."""
    helper = np.eye(3)[np.argmin(np.abs(light))]
    u = np.cross(light, helper)
    u /= np.linalg.norm(u)
    return u, np.cross(light, u)


def _overlaps_in_light_order(plane: np.ndarray, radii: np.ndarray):
    """Pairs (i, j), i < j, of particles already sorted in light order, with j inside i's splat.

    Returns (source i, target j, K_i(x_j)) sorted by target, then source (`_covering_pairs`, ahead only).
    """
    source, target, weight = _covering_pairs(plane, radii, ahead_only=True)
    by_target = np.argsort(target * len(plane) + source)
    return source[by_target], target[by_target], weight[by_target]


def _covering_pairs(plane: np.ndarray, radii: np.ndarray, ahead_only: bool = False):
    """(source i, target j, K_i(x_j)), unsorted: the pairs of particles (already sorted in light order) with j
    inside i's splat, i < j (i ahead of j) only or either way round.  One radius-wide pair query when the radii
    are alike; otherwise sources are bucketed by radius octave so that one huge particle among tiny ones does
    not make every query as wide as itself.
    """
    tree = cKDTree(plane)
    positive = radii > 0
    if not positive.any():
        return np.zeros(0, np.int64), np.zeros(0, np.int64), np.zeros(0)
    largest, smallest = radii.max(), radii[positive].min()
    if largest <= 4.0 * smallest:
        pairs = tree.query_pairs(float(largest), output_type="ndarray")  # i < j guaranteed
        source, target = pairs[:, 0], pairs[:, 1]
        if not ahead_only:
            source, target = np.concatenate([source, target]), np.concatenate([target, source])
    else:
        octave = np.floor(np.log2(np.where(positive, radii, 1.0))).astype(np.int64)
        found_source, found_target = [], []
        for band in np.unique(octave[positive]):
            in_band = np.flatnonzero((octave == band) & positive)
            found = cKDTree(plane[in_band]).sparse_distance_matrix(
                tree, float(radii[in_band].max()), output_type="ndarray"
            )
            found_source.append(in_band[found["i"]])
            found_target.append(found["j"])
        source, target = np.concatenate(found_source), np.concatenate(found_target)
        kept = source < target if ahead_only else source != target
        source, target = source[kept], target[kept]
    offset = plane[target] - plane[source]
    squared = offset[:, 0] ** 2 + offset[:, 1] ** 2
    inside = squared < radii[source] ** 2
    source, target, squared = source[inside], target[inside], squared[inside]
    return source, target, splat_kernel(np.sqrt(squared) / radii[source])


def _incident_exact(plane, toward_light, radii, alpha, sigma, groups):
    """Exact incident light: overlaps found per group, all groups' levels walked together."""
    order, source, target, weight = _overlaps_by_group(plane, toward_light, radii, groups)
    incident = np.empty(len(plane))
    incident[order] = _incident_in_light_order(source, target, weight, alpha[order], sigma[order])
    return incident


def _transmittance_exact(plane, toward_light, radii, alpha, groups, behind=None):
    """(N, K): the product of 1 - alpha_j K_j over the particles j ahead of each (toward the light) whose splat
    covers its centre, for each of the K columns of `alpha` (N, K): the frame buffer of Harris's pass with no
    light scattered on, which needs no light order.  Given `behind` (N, K'), also (N, K') the same product over
    the particles behind each (away from the light), from the same search: (ahead, behind)."""
    pairs = _overlaps_in_light_order if behind is None else _covering_pairs
    order, source, target, weight = _overlaps_by_group(plane, toward_light, radii, groups, pairs)
    ahead = source < target

    def product(columns, chosen):
        blocked = columns[order][source[chosen]] * weight[chosen, None]
        log_through = np.log(np.maximum(1.0 - blocked, np.finfo(np.float64).tiny))
        through = np.empty(columns.shape)
        through[order] = np.exp(
            np.stack([np.bincount(target[chosen], c, minlength=len(plane)) for c in log_through.T], axis=1)
        )
        return through

    if behind is None:
        return product(alpha, ahead)
    return product(alpha, ahead), product(behind, ~ahead)


def _overlaps_by_group(plane, toward_light, radii, groups, pairs=_overlaps_in_light_order):
    """(light order, source, target, K_source(x_target)): the overlaps `pairs` finds (`_overlaps_in_light_order`
    or `_covering_pairs`) group by group, indices into the light order (group-major; ties, coincident particles,
    keep their index order)."""
    n = len(plane)
    order = np.lexsort((np.arange(n), -toward_light, groups))
    plane, radii = plane[order], radii[order]
    sources, targets, weights = [], [], []
    bounds = np.flatnonzero(np.diff(groups[order])) + 1
    for start, stop in zip(np.concatenate([[0], bounds]), np.concatenate([bounds, [n]])):
        source, target, weight = pairs(plane[start:stop], radii[start:stop])
        sources.append(source + start)
        targets.append(target + start)
        weights.append(weight)
    return order, np.concatenate(sources), np.concatenate(targets), np.concatenate(weights)


def _incident_in_light_order(source, target, weight, alpha, sigma):
    """Walk the overlap graph (sources before targets, sorted by target) in dependency levels."""
    n = len(alpha)
    in_source, in_weight = source, weight  # already sorted by target, then source
    in_count = np.bincount(target, minlength=n)
    in_start = np.cumsum(in_count) - in_count

    by_source = np.argsort(source, kind="stable")
    out_target = target[by_source]
    out_count = np.bincount(source, minlength=n)
    out_start = np.cumsum(out_count) - out_count

    incident = np.ones(n)
    waiting = in_count.copy()
    ready = np.flatnonzero(waiting == 0)
    while ready.size:
        lit = ready[in_count[ready] > 0]
        if lit.size:
            edges = concatenated_ranges(in_start[lit], in_count[lit])
            src, w = in_source[edges], in_weight[edges]
            through, scattered = _compose_segments(1.0 - alpha[src] * w, sigma[src] * incident[src] * w, in_count[lit])
            incident[lit] = through + scattered  # the frame buffer starts at 1
        released = out_target[concatenated_ranges(out_start[ready], out_count[ready])]
        np.subtract.at(waiting, released, 1)
        ready = np.unique(released[waiting[released] == 0])
    return incident


def _compose_segments(through: np.ndarray, scattered: np.ndarray, lengths: np.ndarray):
    """Compose v -> through * v + scattered along each segment, first element applied first.

    Inclusive Hillis-Steele scan in log2(longest segment) vectorised passes;
    returns the composite (through, scattered) of each segment.
    """
    through, scattered = through.copy(), scattered.copy()
    ends = np.cumsum(lengths)
    head = np.repeat(ends - lengths, lengths)
    position = np.arange(len(through))
    step = 1
    longest = int(lengths.max())
    while step < longest:
        k = position[position - step >= head]
        earlier_through, earlier_scattered = through[k - step], scattered[k - step]
        scattered[k] = through[k] * earlier_scattered + scattered[k]
        through[k] = through[k] * earlier_through
        step *= 2
    return through[ends - 1], scattered[ends - 1]


# ---------------------------------------------------------------- raster


def _incident_raster(plane, toward_light, radii, alpha, sigma, groups, resolution, slab_fraction):
    """Harris's light-plane frame buffer, one grid per group, visited in depth slabs.

    Inside a slab the splats composite order-independently: transmittance
    T = prod(1 - alpha K) and in-scattered light (1 - T) times the extinction-
    weighted mean of sigma I / alpha.  One splat alone gives the exact blend;
    overlapping ones stay within [0, 1].
    """
    if resolution < 2:
        raise ValueError(f"raster resolution must be >= 2, got {resolution}")
    n = len(plane)
    origin = np.zeros((n, 2))
    cell = np.ones(n)
    grid_offset = np.zeros(n, dtype=np.int64)
    slab = np.zeros(n, dtype=np.int64)
    total_cells = 0
    for group in np.unique(groups):
        members = np.flatnonzero(groups == group)
        low = (plane[members] - radii[members, None]).min(axis=0)
        high = (plane[members] + radii[members, None]).max(axis=0)
        size = max(float((high - low).max()), np.finfo(float).tiny)
        origin[members] = low
        cell[members] = size / resolution
        grid_offset[members] = total_cells
        total_cells += resolution * resolution
        thickness = slab_fraction * float(np.median(radii[members]))
        depth = toward_light[members].max() - toward_light[members]
        slab[members] = (depth / thickness).astype(np.int64) if thickness > 0 else 0

    grid = np.ones(total_cells)
    incident = np.ones(n)
    centre = (plane - origin) / cell[:, None]  # in cells
    for members in _split_by_value(slab):
        incident[members] = _bilinear(grid, grid_offset[members], resolution, centre[members])
        cells, weight, owner = _footprints(centre[members], radii[members] / cell[members], resolution)
        if cells.size == 0:
            continue
        cells = cells + grid_offset[members][owner]
        owner = members[owner]
        extinction = alpha[owner] * weight
        log_through = np.bincount(cells, np.log(np.maximum(1.0 - extinction, 1e-300)), total_cells)
        weighted_extinction = np.bincount(cells, extinction, total_cells)
        weighted_source = np.bincount(cells, sigma[owner] * incident[owner] * weight, total_cells)
        touched = np.flatnonzero(weighted_extinction > 0)
        through = np.exp(log_through[touched])
        source = weighted_source[touched] / weighted_extinction[touched] * (1.0 - through)
        grid[touched] = through * grid[touched] + source
    return incident


def _split_by_value(values: np.ndarray):
    """Index arrays of equal `values`, in increasing value order."""
    order = np.argsort(values, kind="stable")
    bounds = np.flatnonzero(np.diff(values[order])) + 1
    return np.split(order, bounds)


def _bilinear(grid, offset, resolution, point):
    """Grid values (cell centres at i + 0.5) at continuous cell coordinates, clamped to the grid."""
    p = np.clip(point - 0.5, 0.0, resolution - 1.0)
    i0 = np.minimum(p.astype(np.int64), resolution - 2)
    f = p - i0

    def at(dx, dy):
        return grid[offset + (i0[:, 1] + dy) * resolution + i0[:, 0] + dx]

    return (at(0, 0) * (1 - f[:, 0]) + at(1, 0) * f[:, 0]) * (1 - f[:, 1]) + (
        at(0, 1) * (1 - f[:, 0]) + at(1, 1) * f[:, 0]
    ) * f[:, 1]


def _footprints(centre, radius, resolution):
    """Cells whose centres lie inside each splat: (cell index, kernel weight, owning splat).

    The cells tried are those whose centres (i + 0.5) can lie within a radius of the splat's centre, at most a
    cell more than those that do: the raster's time is mostly these cells (docs/shading.md)."""
    low = np.clip(np.ceil(centre - radius[:, None] - 0.5).astype(np.int64), 0, resolution - 1)
    high = np.clip(np.floor(centre + radius[:, None] - 0.5).astype(np.int64), 0, resolution - 1)
    span = np.maximum(high - low + 1, 0)
    count = span[:, 0] * span[:, 1]
    owner = np.repeat(np.arange(len(centre)), count)
    local = np.arange(int(count.sum())) - np.repeat(np.cumsum(count) - count, count)
    x = low[owner, 0] + local % span[owner, 0]
    y = low[owner, 1] + local // span[owner, 0]
    with np.errstate(divide="ignore", invalid="ignore"):
        d = np.hypot(x + 0.5 - centre[owner, 0], y + 0.5 - centre[owner, 1]) / radius[owner]
    inside = np.flatnonzero(d < 1.0)  # a splat of radius 0 covers nothing: its d is NaN or infinite
    weight = splat_kernel(d[inside])
    keep = inside[weight > 0]
    return (y * resolution + x)[keep], weight[weight > 0], owner[keep]

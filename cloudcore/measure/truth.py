"""Ground truth for the shading models: the clouds as a heterogeneous medium, path traced by Mitsuba 3.

Each particle becomes a blob of extinction with the splat kernel's profile (`cloudcore.maths.splat_kernel`),

    sigma_t(x) = c_i K(|x - p_i| / r_i),    c_i = tau_i / (r_i * KERNEL_DIAMETER_INTEGRAL),

so that the optical depth along a diameter, the line integral through the centre, is the particle's
tau (Harris's alpha = 1 - exp(-tau) is the opacity of a splat at its centre).  Overlapping particles
add their extinction.  The extinction is sampled at voxel centres over boxes around the clouds (one
box per set of clouds whose boxes overlap, so that empty air between clouds costs the path tracer
nothing: Mitsuba's heterogeneous medium tracks free paths against the largest extinction of its
grid); the albedo is the extinction-weighted mean of the particles' albedos, the phase function the
scene's.

The light is the model's: the sun and the skylight as directional emitters with the irradiance the
model gives them, and the ambient term as a constant environment of that radiance (a cloud of albedo 1
in it returns exactly the model's ambient * (1 - T)).  The emitters are hidden from camera rays; the
background, the sky the renderer draws (`cloudcore.light.sky_background`: the atmosphere's with the sun's disc,
or the gradient), is added behind the clouds with their transmittance T, computed here by marching the same
grid, where the pixel's ray misses the terrain.

With `render_truth(terrain=True)` the scene's heightfield terrain is a Lambertian mesh of the colours the
renderer gives it (its ramp by height, its steep colour by slope): the clouds shadow it, it sends light back up
into them, and what the eye sees of it is path traced with the clouds in front of it.  Its radiance is a
physical surface's, albedo E cos / pi, where the renderer's terrain colour is albedo E (the renderer's values):
compare the ground's light with and without the clouds, not its level.

Mitsuba is imported only inside the
functions that need it (`cloudview[truth]`), so importing this module never needs it.
"""

from __future__ import annotations

import dataclasses
import time
from dataclasses import dataclass

import numpy as np

from cloudcore.light.illumination import cloud_optics
from cloudcore.light.lighting import active_lights, scene_lights
from cloudcore.light.phase import phase_function
from cloudcore.light.sky_background import scene_sky
from cloudcore.maths.segments import concatenated_ranges
from cloudcore.maths.splat_kernel import KERNEL_DIAMETER_INTEGRAL, splat_kernel
from cloudcore.model.scene import Camera, Scene, Terrain
from cloudcore.world.camera import FAR_PLANE_M, NEAR_PLANE_M, camera_pose, pixel_rays
from cloudcore.world.terrain import ground_colours, heightfield_mesh, samples_across

#: voxels across the scene's median particle radius: the line integral through a particle's centre is
#: within 1% of its tau at 3 (tests/unit/measure/test_truth.py); the default scene then has about 10 million voxels
DEFAULT_VOXELS_PER_RADIUS = 3.0
#: (a, b) of `resolution_gain`, and the radius in voxels below which it stays constant
RESOLUTION_GAIN_FIT = (1.46, 2.72)
MIN_RADIUS_VOXELS = 1.5
#: voxels along a side of one brick of the medium (`_bricks`)
BRICK_VOXELS = 16
#: more voxels than this is refused rather than filling the memory (float64 while built, float32 in Mitsuba)
MAX_VOXELS = 60_000_000
#: Mitsuba variants, the default first: the scalar one runs anywhere; the vectorised LLVM one needs
#: libLLVM and, on this project's 2-core Xeon with Mesa's LLVM 15, aborts the process compiling its
#: first kernel ("Cannot select"), which no exception can catch, so it is only taken when asked for
VARIANTS = ("scalar_rgb", "llvm_ad_rgb")
#: samples per pixel of one Mitsuba render call; the progress bar advances once per call
SAMPLES_PER_PASS = 16
#: a phase function Mitsuba lacks (Cornette-Shanks) goes in as a table over cos(theta) of this many points
PHASE_TABLE_POINTS = 4097
#: ray-marching step of the transmittance, in voxels (midpoint rule on the trilinear field)
MARCH_STEP_VOXELS = 0.5
#: where Mitsuba's Russian roulette starts: never.  From its default depth (5) it keeps a path with probability
#: its weight, capped at 0.95, and divides by that, so in a thick medium of albedo near 1 a path's weight grows
#: 1/0.95 a bounce while it survives: the light is carried by a few long walks that a few dozen samples a pixel
#: miss, and the picture comes out too dark (a thick slab at albedo 0.999 by 12%, docs/shading.md, "The truth's
#: estimator").  Paths end by leaving the medium, or at `path_depth`.
NO_ROULETTE_DEPTH = 2**31 - 1
#: a path is followed until its weight, albedo^depth, falls below this: what it could still carry
PATH_WEIGHT_CUTOFF = 1e-4


def path_depth(albedo: float) -> int:
    """Mitsuba's max_depth where no bounce keeps more than `albedo` of the light (the media's single-scattering
    albedo, the ground's reflectance): one past the depth at which a path's weight albedo^depth falls below
    PATH_WEIGHT_CUTOFF, and at least 2 (the light gathered at the first bounce); -1 (no limit) at albedo 1, where
    paths end only by leaving the medium."""
    if albedo >= 1.0:
        return -1
    if albedo <= PATH_WEIGHT_CUTOFF:
        return 2
    return max(2, int(np.ceil(np.log(PATH_WEIGHT_CUTOFF) / np.log(albedo))) + 1)


def peak_extinction(optical_depth, radii) -> np.ndarray:
    """c_i: the extinction (1/m) at a particle's centre that gives optical depth tau_i along its diameter."""
    return np.asarray(optical_depth, dtype=np.float64) / (
        np.asarray(radii, dtype=np.float64) * KERNEL_DIAMETER_INTEGRAL
    )


@dataclass(frozen=True, eq=False)
class MediumGrid:
    """One brick of the medium: extinction and albedo at the centres of cubic voxels, voxel (i, j, k)
    centred at low + (i + 0.5, j + 0.5, k + 0.5) * voxel, arrays indexed [z, y, x] as Mitsuba's
    VolumeGrid.  The brick owns the box [box_low, box_high]; its arrays reach one voxel further on
    each side where there is more grid, so that interpolation inside the box sees its neighbours."""

    low: np.ndarray
    voxel: float
    extinction: np.ndarray
    albedo: np.ndarray
    box_low: np.ndarray
    box_high: np.ndarray

    @property
    def shape_xyz(self) -> np.ndarray:
        return np.array(self.extinction.shape[::-1])

    @property
    def high(self) -> np.ndarray:
        return self.low + self.voxel * self.shape_xyz

    def sample(self, points: np.ndarray) -> np.ndarray:
        """Extinction at `points` (n, 3), trilinear between voxel centres and clamped at the faces, as
        Mitsuba's gridvolume evaluates it (its texel centres are at (i + 0.5) / resolution)."""
        u = np.clip((points - self.low) / self.voxel - 0.5, 0.0, self.shape_xyz - 1.0)
        first = np.minimum(u.astype(np.int64), self.shape_xyz - 2)
        f = u - first
        nz, ny, nx = self.extinction.shape
        flat = self.extinction.reshape(-1)
        value = np.zeros(len(points))
        for dx in (0, 1):
            for dy in (0, 1):
                for dz in (0, 1):
                    weight = (
                        (f[:, 0] if dx else 1.0 - f[:, 0])
                        * (f[:, 1] if dy else 1.0 - f[:, 1])
                        * (f[:, 2] if dz else 1.0 - f[:, 2])
                    )
                    index = ((first[:, 2] + dz) * ny + first[:, 1] + dy) * nx + first[:, 0] + dx
                    value += weight * flat[index]
        return value


def medium_grids(
    scene: Scene, voxels_per_radius: float = DEFAULT_VOXELS_PER_RADIUS, brick_voxels: int = BRICK_VOXELS
) -> list[MediumGrid]:
    """The scene's particles as one extinction grid, cut into bricks of `brick_voxels` a side, the empty
    ones dropped.

    Voxels are cubes of the scene's median particle radius / `voxels_per_radius`; the grid has one
    empty voxel around the particles' reach, so it is zero where Mitsuba clamps at its faces.
    """
    if not voxels_per_radius > 0:
        raise ValueError(f"voxels per radius must be > 0, got {voxels_per_radius}")
    parts = []
    for cloud in scene.clouds:
        tau, albedo = cloud_optics(cloud, scene.shading)
        keep = (cloud.radii > 0) & (tau > 0)
        if keep.any():
            parts.append((cloud.centres[keep], cloud.radii[keep], tau[keep], albedo[keep]))
    if not parts:
        return []
    centres, radii, tau, albedo = (np.concatenate(column) for column in zip(*parts))
    voxel = float(np.median(radii)) / voxels_per_radius
    low, shape_xyz = splat_grid_box(centres, radii, voxel)
    peak = peak_extinction(tau, radii) * resolution_gain(radii / voxel)
    extinction, albedo_grid = splatted_extinction(low, voxel, shape_xyz, centres, radii, peak, albedo)
    return _bricks(low, voxel, extinction, albedo_grid, brick_voxels)


def splat_grid_box(centres, radii, voxel: float) -> tuple[np.ndarray, np.ndarray]:
    """(low corner, shape (x, y, z) in voxels) of a grid of cubic `voxel`s over the particles' reach with one
    empty voxel around it, so that the grid is zero at its faces; ValueError past MAX_VOXELS."""
    low = (centres - radii[:, None]).min(axis=0) - voxel
    high = (centres + radii[:, None]).max(axis=0) + voxel
    shape_xyz = np.maximum(np.ceil((high - low) / voxel).astype(np.int64), 2)
    if int(np.prod(shape_xyz)) > MAX_VOXELS:
        raise ValueError(
            f"the medium would need {int(np.prod(shape_xyz)):,} voxels (at most {MAX_VOXELS:,}): "
            "ask for fewer voxels per radius"
        )
    return low, shape_xyz


def _bricks(low, voxel, extinction, albedo, brick_voxels: int) -> list[MediumGrid]:
    """The grid's non-empty bricks, each with a one-voxel border of its neighbours' voxels.

    Mitsuba tracks free paths in a medium against the largest extinction of its whole grid: one grid
    over the scene would spend most of its steps in the clear air between the clouds.
    """
    bricks = []
    shape_zyx = np.array(extinction.shape)
    # Mitsuba starts a ray that leaves a surface (1 + |p|) * 9e-5 past it (float32): a neighbour's face
    # closer than that would be skipped, and its medium with it.  So the boxes keep twice that apart,
    # losing that sliver of cloud (0.4 m a brick at 2 km from the origin: 0.3% of a 160 m brick).
    gap = 2.0 * (1.0 + float(np.abs(np.concatenate([low, low + voxel * shape_zyx[::-1]])).max())) * 9e-5
    for z, y, x in np.ndindex(*(-(-shape_zyx // brick_voxels))):
        start = np.array([z, y, x]) * brick_voxels
        stop = np.minimum(start + brick_voxels, shape_zyx)
        inner = tuple(slice(a, b) for a, b in zip(start, stop))
        if not extinction[inner].any():
            continue
        border_start, border_stop = np.maximum(start - 1, 0), np.minimum(stop + 1, shape_zyx)
        outer = tuple(slice(a, b) for a, b in zip(border_start, border_stop))
        bricks.append(
            MediumGrid(
                low=low + border_start[::-1] * voxel,
                voxel=voxel,
                extinction=extinction[outer],
                albedo=albedo[outer],
                box_low=low + start[::-1] * voxel + 0.5 * gap,
                box_high=low + stop[::-1] * voxel - 0.5 * gap,
            )
        )
    return bricks


def resolution_gain(radii_in_voxels) -> np.ndarray:
    """What a particle's peak extinction is multiplied by on a grid of voxels a fraction of its radius.

    Interpolating between voxel centres blurs the kernel across a ray, always a loss of optical depth
    through the centre: measured over random centres and directions (tests/unit/measure/test_truth.py), 16.4% of tau
    at 3 voxels a radius, 9.3% at 4, 4.2% at 6, 2.3% at 8.  1 + a / q^2 + b / q^4 in the radius in
    voxels q, fitted to those four, gives the inverse within 0.5%; below 1.5 voxels a radius the grid
    cannot hold a particle's shape and the gain stops growing.
    """
    q = np.maximum(np.asarray(radii_in_voxels, dtype=np.float64), MIN_RADIUS_VOXELS)
    return 1.0 + RESOLUTION_GAIN_FIT[0] / q**2 + RESOLUTION_GAIN_FIT[1] / q**4


def splatted_extinction(
    low, voxel, shape_xyz, centres, radii, peak, albedo, chunk_entries: int = 2_000_000
) -> tuple[np.ndarray, np.ndarray]:
    """(extinction, albedo) [z, y, x]: every particle's `peak` K(d) summed at the centres of the voxels it
    reaches, voxel (i, j, k) centred at low + (i + 0.5, j + 0.5, k + 0.5) * voxel; the albedo weighted by
    extinction."""
    count = int(np.prod(shape_xyz))
    extinction = np.zeros(count)
    scattering = np.zeros(count)
    first = np.clip(np.floor((centres - radii[:, None] - low) / voxel - 0.5).astype(np.int64), 0, shape_xyz - 1)
    last = np.clip(np.ceil((centres + radii[:, None] - low) / voxel - 0.5).astype(np.int64), 0, shape_xyz - 1)
    spans = (last - first + 1).max(axis=1)
    for span in np.unique(spans):
        members = np.flatnonzero(spans == span)
        offsets = np.stack(np.meshgrid(*[np.arange(span)] * 3, indexing="ij"), axis=-1).reshape(-1, 3)
        step = max(1, chunk_entries // len(offsets))
        for start in range(0, len(members), step):
            part = members[start : start + step]
            index = first[part, None, :] + offsets[None]
            inside = np.all(index < shape_xyz, axis=2)
            distance = np.linalg.norm(low + (index + 0.5) * voxel - centres[part, None, :], axis=2)
            value = peak[part, None] * splat_kernel(distance / radii[part, None])
            keep = inside & (value > 0)
            flat = ((index[..., 2] * shape_xyz[1] + index[..., 1]) * shape_xyz[0] + index[..., 0])[keep]
            extinction += np.bincount(flat, value[keep], count)
            scattering += np.bincount(flat, (value * albedo[part, None])[keep], count)
    # where nothing is, the albedo does not matter; the mean keeps interpolated edges from darkening
    total = extinction.sum()
    mean_albedo = float(scattering.sum() / total) if total > 0 else float(albedo.mean())
    with np.errstate(invalid="ignore", divide="ignore"):
        albedo_grid = np.where(extinction > 0, scattering / extinction, mean_albedo)
    zyx = tuple(shape_xyz[::-1])
    return extinction.reshape(zyx), albedo_grid.reshape(zyx)


# ---------------------------------------------------------------- transmittance by marching the grid


def optical_depths(
    grids: list[MediumGrid],
    origins: np.ndarray,
    directions: np.ndarray,
    chunk_rays: int = 2048,
    stops: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """(total optical depth (n,), distance (n,) at which it first reaches 1, inf where it never does)
    along rays from `origins` (n, 3) in unit `directions` (n, 3), marched through every grid, each to its
    distance of `stops` (n,: where it meets the terrain; inf, the default, through everything).

    Midpoint rule with a step of `MARCH_STEP_VOXELS` voxels on one lattice of distances shared by all
    grids, so the depths of the grids a ray crosses add up in the order it meets them.
    """
    origins = np.asarray(origins, dtype=np.float64).reshape(-1, 3)
    directions = np.asarray(directions, dtype=np.float64).reshape(-1, 3)
    n = len(origins)
    total, unit_distance = np.zeros(n), np.full(n, np.inf)
    if not grids or n == 0:
        return total, unit_distance
    step = MARCH_STEP_VOXELS * min(grid.voxel for grid in grids)
    stops = np.full(n, np.inf) if stops is None else np.asarray(stops, dtype=np.float64).reshape(n)
    for start in range(0, n, chunk_rays):
        rays = slice(start, min(start + chunk_rays, n))
        o, d = origins[rays], directions[rays]
        segments = [
            (t0, np.minimum(t1, stops[rays]))
            for t0, t1 in (_ray_box(o, d, grid.box_low, grid.box_high) for grid in grids)
        ]
        far = max(float(np.max(np.where(t1 > t0, t1, 0.0))) for t0, t1 in segments)
        columns = int(np.ceil(far / step)) + 1
        depth = np.zeros((len(o), columns))
        for grid, (t0, t1) in zip(grids, segments):
            crossed = t1 > t0  # a missed box has t1 <= t0, possibly infinite
            first = np.where(crossed, np.ceil(t0 / step - 0.5), 0).astype(np.int64)
            last = np.where(crossed, np.floor(t1 / step - 0.5), -1).astype(np.int64)
            counts = np.maximum(last - first + 1, 0)
            if not counts.any():
                continue
            ray = np.repeat(np.arange(len(o)), counts)
            column = concatenated_ranges(first[counts > 0], counts[counts > 0])
            points = o[ray] + ((column + 0.5) * step)[:, None] * d[ray]
            depth[ray, column] += grid.sample(points) * step
        cumulative = np.cumsum(depth, axis=1)
        total[rays] = cumulative[:, -1]
        reached = cumulative[:, -1] >= 1.0
        found = np.argmax(cumulative >= 1.0, axis=1)
        unit_distance[start : start + len(o)] = np.where(reached, (found + 0.5) * step, np.inf)
    return total, unit_distance


def _ray_box(origins, directions, low, high) -> tuple[np.ndarray, np.ndarray]:
    """Slab intersection: (entry, exit) distances of each ray with the box, entry clamped to 0."""
    with np.errstate(divide="ignore", invalid="ignore"):
        inverse = 1.0 / directions
        a, b = (low - origins) * inverse, (high - origins) * inverse
    near = np.nan_to_num(np.minimum(a, b), nan=-np.inf).max(axis=1)
    far = np.nan_to_num(np.maximum(a, b), nan=np.inf).min(axis=1)
    return np.maximum(near, 0.0), far


# ---------------------------------------------------------------- the Mitsuba scene


def mitsuba_variant(preferred: str | None = None) -> str:
    """Set and return `preferred`, or else the first of `VARIANTS` that loads here."""
    import mitsuba as mi

    errors = []
    for variant in (preferred,) if preferred else VARIANTS:
        try:
            mi.set_variant(variant)
            return variant
        except (ImportError, AttributeError, RuntimeError, ValueError) as error:
            errors.append(f"{variant}: {error}")
    raise RuntimeError("no Mitsuba variant loads here (" + "; ".join(errors) + ")")


def phase_description(phase: str, g: float) -> dict:
    """The scene's phase function as a Mitsuba plugin: its own Rayleigh and Henyey-Greenstein, and
    Cornette-Shanks (which it lacks) as a table; both normalise theirs to 1 / (4 pi) of our mean-1 form."""
    if phase == "rayleigh":
        return {"type": "rayleigh"}
    if phase == "henyey-greenstein":
        return {"type": "hg", "g": float(g)}
    table = phase_function(np.linspace(-1.0, 1.0, PHASE_TABLE_POINTS), phase, g)
    return {"type": "tabphase", "values": ",".join(f"{v:.9g}" for v in table)}


def mitsuba_scene_description(
    grids: list[MediumGrid],
    scene: Scene,
    camera: Camera,
    width: int,
    height: int,
    *,
    time_of_day: float | None = None,
    max_depth: int | None = None,
    ground=None,
) -> dict:
    """The `mi.load_dict` description: the grids in null-bounded cubes, the model's lights, the camera, and
    `ground` (`terrain_shape`'s) when given.  `max_depth` (-1: no limit) bounds the paths; by default
    `path_depth` of the grids' largest albedo.

    Call `mitsuba_variant` first (the dictionary holds Mitsuba objects of that variant).
    """
    import mitsuba as mi

    lighting = scene.lighting if time_of_day is None else dataclasses.replace(scene.lighting, time_of_day=time_of_day)
    lights, ambient = scene_lights(lighting)
    phase = phase_description(scene.shading.phase, scene.shading.g)
    description = {
        "type": "scene",
        "integrator": integrator_description(_largest_albedo(grids, scene, ground is not None), max_depth),
        "sensor": _sensor(mi, camera, width, height, grids),
        "ambient": {"type": "constant", "radiance": {"type": "rgb", "value": [float(v) for v in ambient]}},
    }
    for number, light in enumerate(active_lights(lights)):
        description[f"light_{number}"] = {
            "type": "directional",
            "direction": [-float(v) for v in light.direction],  # Mitsuba's points the way the light travels
            "irradiance": {"type": "rgb", "value": [float(c) * light.intensity for c in light.color]},
        }
    for number, grid in enumerate(grids):
        description[f"cloud_{number}"] = {
            "type": "cube",
            "to_world": _box_transform(mi, grid, unit_cube=False),
            "bsdf": {"type": "null"},
            # named so that a sensor inside the box can start in it
            "interior": _medium(mi, grid, phase) | {"id": f"cloud_{number}_medium"},
        }
    if ground is not None:
        description["terrain"] = ground
    return description


def _largest_albedo(grids: list[MediumGrid], scene: Scene, with_ground: bool) -> float:
    """The largest share of light any bounce keeps: the media's single-scattering albedo, the ground's colour."""
    ground = ground_albedo(scene.terrain) if with_ground and scene.terrain is not None else 0.0
    return max([float(ground), *(float(grid.albedo.max()) for grid in grids)])


def integrator_description(albedo: float, max_depth: int | None = None) -> dict:
    """The truth's path tracer for a medium whose largest single-scattering albedo is `albedo`: Mitsuba's volpath
    without Russian roulette (`NO_ROULETTE_DEPTH`), paths bounded by `max_depth` (-1: no limit; by default
    `path_depth(albedo)`), the emitters hidden from camera rays (the sky is composited behind the clouds with their
    transmittance)."""
    return {
        "type": "volpath",
        "max_depth": path_depth(albedo) if max_depth is None else int(max_depth),
        "rr_depth": NO_ROULETTE_DEPTH,
        "hide_emitters": True,
    }


def terrain_shape(terrain: Terrain):
    """The heightfield `terrain` as a Mitsuba mesh (the renderer's: `cloudcore.world.terrain.heightfield_mesh`), its
    faces up, Lambertian of the ground's colours the renderer gives it (`cloudcore.world.terrain.ground_colours`: its
    ramp by height and its steep colour by slope), interpolated between the vertices.  Call `mitsuba_variant` first."""
    import mitsuba as mi

    vertices, faces = heightfield_mesh(terrain)
    mesh = mi.Mesh("terrain", len(vertices), len(faces), has_vertex_normals=False, has_vertex_texcoords=False)
    parameters = mi.traverse(mesh)
    parameters["vertex_positions"] = np.ascontiguousarray(vertices, dtype=np.float32).ravel()
    parameters["faces"] = np.ascontiguousarray(faces, dtype=np.uint32).ravel()
    parameters.update()
    colours = ground_colours(terrain, vertices, _heightfield_normals(terrain, vertices))
    mesh.add_attribute("vertex_color", 3, np.ascontiguousarray(colours, dtype=np.float32).ravel())
    mesh.set_bsdf(mi.load_dict({"type": "diffuse", "reflectance": {"type": "mesh_attribute", "name": "vertex_color"}}))
    return mesh


def _heightfield_normals(terrain: Terrain, vertices: np.ndarray) -> np.ndarray:
    """(n, 3) unit normals of `heightfield_mesh`'s vertices, by differences over its grid (one-sided at its edges)."""
    across, rows = samples_across(terrain)
    heights = vertices[:, 1].reshape(rows, across)
    slope_z, slope_x = np.gradient(heights, terrain.size[1] / (rows - 1), terrain.size[0] / (across - 1))
    normals = np.stack([-slope_x, np.ones_like(slope_x), -slope_z], axis=-1).reshape(-1, 3)
    return normals / np.linalg.norm(normals, axis=1, keepdims=True)


def ground_albedo(terrain: Terrain) -> float:
    """The most light any of the ground's colours keeps at a bounce: its colour or its ramp's, and its steep one."""
    colours = [terrain.color, *(row[1:] for row in terrain.color_ramp or ())]
    if terrain.steep_color is not None:
        colours.append(terrain.steep_color)
    return float(np.max(colours))


def _medium(mi, grid: MediumGrid, phase: dict) -> dict:
    volume_to_world = _box_transform(mi, grid, unit_cube=True)
    albedo = grid.albedo
    uniform = float(albedo.min()) == float(albedo.max())
    return {
        "type": "heterogeneous",
        "sigma_t": {
            "type": "gridvolume",
            "grid": mi.VolumeGrid(np.ascontiguousarray(grid.extinction, dtype=np.float32)),
            "to_world": volume_to_world,
        },
        "albedo": float(albedo.flat[0])
        if uniform
        else {
            "type": "gridvolume",
            "grid": mi.VolumeGrid(np.ascontiguousarray(albedo, dtype=np.float32)),
            "to_world": volume_to_world,
        },
        "phase": phase,
    }


def _box_transform(mi, grid: MediumGrid, *, unit_cube: bool):
    """The brick's data from Mitsuba's unit cube [0, 1]^3 (volumes), or its box from the cube shape's
    [-1, 1]^3."""
    low, high = (grid.low, grid.high) if unit_cube else (grid.box_low, grid.box_high)
    matrix = np.eye(4)
    if unit_cube:
        matrix[:3, :3], matrix[:3, 3] = np.diag(high - low), low
    else:
        matrix[:3, :3], matrix[:3, 3] = np.diag(0.5 * (high - low)), 0.5 * (low + high)
    return mi.ScalarTransform4f(matrix.tolist())


def _sensor(mi, camera: Camera, width: int, height: int, grids: list[MediumGrid]) -> dict:
    """A perspective camera with `cloudcore.world.camera`'s pose and vertical field of view.

    Mitsuba's camera looks down its +z with +y up and +x to the image's left (its look_at puts
    cross(up, forward) there), so the pose's columns are (-right, up, forward, eye).
    """
    pose = camera_pose(camera)
    matrix = np.eye(4)
    matrix[:3, 0], matrix[:3, 1], matrix[:3, 2], matrix[:3, 3] = -pose[:3, 0], pose[:3, 1], -pose[:3, 2], pose[:3, 3]
    sensor = {
        "type": "perspective",
        "fov": float(camera.fov_y_deg),
        "fov_axis": "y",
        "near_clip": NEAR_PLANE_M,
        "far_clip": FAR_PLANE_M,
        "to_world": mi.ScalarTransform4f(matrix.tolist()),
        "film": {
            "type": "hdrfilm",
            "width": int(width),
            "height": int(height),
            "pixel_format": "rgb",
            # one box per pixel, as the GL frame's one sample at each pixel centre covers its pixel
            "rfilter": {"type": "box"},
        },
        "sampler": {"type": "independent", "sample_count": SAMPLES_PER_PASS},
    }
    eye = np.asarray(camera.position, dtype=np.float64)
    inside = [i for i, grid in enumerate(grids) if np.all(eye > grid.box_low) and np.all(eye < grid.box_high)]
    if inside:
        # an eye inside a cloud's box starts in its medium (the box's faces are crossed only on the way out)
        sensor["medium"] = {"type": "ref", "id": f"cloud_{inside[0]}_medium"}
    return sensor


# ---------------------------------------------------------------- the truth image


@dataclass(frozen=True)
class Truth:
    """A path-traced picture: linear RGB (height, width, 3) with the sky behind, and what it was made of."""

    linear: np.ndarray
    #: (height, width, 3): the light the clouds send to the eye alone (the path-traced part of `linear`)
    radiance: np.ndarray
    #: (height, width): 1 - the transmittance of the clouds along each pixel's central ray
    alpha: np.ndarray
    #: (height, width): optical depth toward the sun from the point where the view ray's reaches 1
    #: (inf where it never does, or without a sun)
    sun_depth: np.ndarray
    #: (height, width): the distance along each pixel's central ray to the terrain (inf where it misses it, or
    #: without one)
    ground_distance: np.ndarray
    seconds: float
    variant: str
    voxels: int
    spp: int
    seed: int


def pass_samples(spp: int) -> list[int]:
    """Samples per pixel of each Mitsuba render call of a truth of `spp`: `SAMPLES_PER_PASS` each, the last
    the rest."""
    if spp < 1:
        raise ValueError(f"samples per pixel must be >= 1, got {spp}")
    return [min(SAMPLES_PER_PASS, spp - done) for done in range(0, spp, SAMPLES_PER_PASS)]


class PathTracer:
    """The Mitsuba scene of a truth render, and its passes.

    Pass k of a render of `seed` is seeded with (seed << 16) + k, so a pass gives the same samples wherever it
    runs (`cloudview truth --workers` spreads them over processes) and two seeds share none.  The Mitsuba
    scene is loaded on the first pass: the compositing needs only the grids and the ground.
    """

    def __init__(
        self,
        scene: Scene,
        width: int,
        height: int,
        *,
        camera: Camera | None = None,
        time_of_day: float | None = None,
        voxels_per_radius: float = DEFAULT_VOXELS_PER_RADIUS,
        variant: str | None = None,
        max_depth: int | None = None,
        terrain: bool = False,
        grids: list[MediumGrid] | None = None,
    ):
        """`grids`: the medium, where it is built already (`medium_grids`'s); otherwise built here."""
        self.camera = scene.camera if camera is None else camera
        self.variant = mitsuba_variant(variant)
        self.grids = medium_grids(scene, voxels_per_radius) if grids is None else grids
        self.ground = terrain_shape(scene.terrain) if terrain and scene.terrain is not None else None
        self._describe = lambda: mitsuba_scene_description(
            self.grids,
            scene,
            self.camera,
            width,
            height,
            time_of_day=time_of_day,
            max_depth=max_depth,
            ground=self.ground,
        )
        self._loaded = None

    def pass_radiance(self, number: int, samples: int, seed: int) -> np.ndarray:
        """(height, width, 3) float64: pass `number`'s mean radiance times its `samples`, so passes add up."""
        import mitsuba as mi

        if self._loaded is None:
            self._loaded = mi.load_dict(self._describe())
        image = mi.render(self._loaded, spp=samples, seed=(seed << 16) + number)
        return np.asarray(image, dtype=np.float64) * samples


def render_truth(
    scene: Scene,
    width: int,
    height: int,
    *,
    camera: Camera | None = None,
    time_of_day: float | None = None,
    spp: int = 64,
    seed: int = 0,
    voxels_per_radius: float = DEFAULT_VOXELS_PER_RADIUS,
    variant: str | None = None,
    max_depth: int | None = None,
    progress=None,
    terrain: bool = False,
    run_passes=None,
) -> Truth:
    """Path trace `scene` (its clouds, sky and, with `terrain`, its heightfield terrain; no objects) from
    `camera` (the scene's).

    `spp` samples per pixel in the passes of `pass_samples`, seeded as `PathTracer` says, so a seed gives the
    same picture every time.  `run_passes(samples, grids)`, given the samples of each pass and the medium, gives
    each pass's `PathTracer.pass_radiance` in order, run elsewhere (by default here); they are added in that order.
    `progress(done, total)` is called after each pass.
    """
    samples = pass_samples(spp)
    camera = scene.camera if camera is None else camera
    start = time.perf_counter()
    tracer = PathTracer(
        scene,
        width,
        height,
        camera=camera,
        time_of_day=time_of_day,
        voxels_per_radius=voxels_per_radius,
        variant=variant,
        max_depth=max_depth,
        terrain=terrain,
    )
    if run_passes is None:
        passes = (tracer.pass_radiance(number, count, seed) for number, count in enumerate(samples))
    else:
        passes = run_passes(samples, tracer.grids)
    radiance = np.zeros((height, width, 3))
    done = 0
    for count, weighted in zip(samples, passes, strict=True):
        radiance += weighted
        done += count
        if progress is not None:
            progress(done, spp)
    radiance /= spp

    grids, ground = tracer.grids, tracer.ground
    lighting = scene.lighting if time_of_day is None else dataclasses.replace(scene.lighting, time_of_day=time_of_day)
    rays = pixel_rays(camera, width, height).reshape(-1, 3)
    eye = np.broadcast_to(np.asarray(camera.position, dtype=np.float64), rays.shape)
    ground_distance = _ground_distances(ground, eye, rays)
    view_depth, unit_distance = optical_depths(grids, eye, rays, stops=ground_distance)
    transmittance = np.exp(-view_depth).reshape(height, width)
    sky = scene_sky(lighting).seen_from(camera.position).radiance(rays, np.radians(camera.fov_y_deg) / height)
    sky = sky.reshape(height, width, 3)
    sky[np.isfinite(ground_distance).reshape(height, width)] = 0.0  # the terrain's light is path traced
    radiance = np.nan_to_num(radiance, nan=0.0, posinf=0.0, neginf=0.0)
    return Truth(
        linear=radiance + transmittance[..., None] * sky,
        radiance=radiance,
        alpha=1.0 - transmittance,
        sun_depth=_sun_depths(grids, eye, rays, unit_distance, lighting).reshape(height, width),
        ground_distance=ground_distance.reshape(height, width),
        seconds=time.perf_counter() - start,
        variant=tracer.variant,
        voxels=sum(grid.extinction.size for grid in grids),
        spp=spp,
        seed=seed,
    )


def _ground_distances(ground, eye, rays) -> np.ndarray:
    """(n,): the distance along each of `rays` from `eye` (n, 3 each) to the `ground` mesh (`terrain_shape`'s;
    inf where it misses, or without one), traced by Mitsuba ray by ray (its scalar variant's way)."""
    distances = np.full(len(rays), np.inf)
    if ground is None:
        return distances
    import mitsuba as mi

    alone = mi.load_dict({"type": "scene", "terrain": ground})
    # Mitsuba's float32 ray-triangle test is not watertight: a central ray through an edge of the mesh can slip
    # between its two triangles, so a miss is traced again from a millimetre aside before it counts
    aside = np.array([1e-3, 0.0, 1e-3])
    for i, (origin, direction) in enumerate(zip(eye, rays, strict=True)):
        for start in (origin, origin + aside):
            hit = alone.ray_intersect(mi.Ray3f(mi.Point3f(start.tolist()), mi.Vector3f(direction.tolist())))
            if bool(hit.is_valid()):
                distances[i] = float(hit.t)
                break
    return distances


def _sun_depths(grids, eye, rays, unit_distance, lighting) -> np.ndarray:
    """Optical depth toward the sun (the first light) from each ray's unit-depth point (inf where none)."""
    lights, _ = scene_lights(lighting)
    lights = active_lights(lights)
    depth = np.full(len(rays), np.inf)
    seen = np.isfinite(unit_distance)
    if lights and seen.any():
        points = eye[seen] + unit_distance[seen, None] * rays[seen]
        toward = np.broadcast_to(np.asarray(lights[0].direction, dtype=np.float64), points.shape)
        depth[seen] = optical_depths(grids, points, toward)[0]
    return depth

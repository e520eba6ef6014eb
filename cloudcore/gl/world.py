"""The world pass: the terrain's tiles, lit per vertex and seen through the air, then the sky where they leave it.

The terrain is drawn straight into the linear target with its depth (shaders/terrain.*.glsl): its tiles
follow the eye (`cloudcore.world.terrain_tiles`), their light is baked per vertex (`TerrainLight`, the sun's part
apart), and under the physical sky the air between the eye and each vertex is read per vertex.  The sky
follows, a full-screen triangle at the far plane that the depth test keeps off the terrain (shaders/sky.frag.glsl,
compiled for the sky it draws).  Where each millisecond went before, and what this cut: docs/performance.md,
"The world pass: where its time goes".
"""

from __future__ import annotations

import ctypes
import itertools
from collections.abc import Callable

import numpy as np
from OpenGL import GL

from cloudcore.atmosphere.aerial_perspective import FAR_AIR_FROM, MAX_DISTANCE_M
from cloudcore.atmosphere.geometry import horizon_cosine
from cloudcore.atmosphere.sky_view import eye_radius, horizon_angles
from cloudcore.atmosphere.sun_disc import SUN_ANGULAR_RADIUS
from cloudcore.gl.air_volume import AirVolume
from cloudcore.gl.context import HeadlessContext
from cloudcore.gl.ground_shadows import GroundShadows
from cloudcore.gl.light_shafts import LightShaftPass
from cloudcore.gl.programs import ProgramCache, set_matrix, set_vec3
from cloudcore.gl.shadow_map import CloudShadowMap
from cloudcore.gl.targets import TextureTarget, linear_filtering
from cloudcore.light.air_between import AirBetween, air_between
from cloudcore.light.cloud_shadows import LightSpace
from cloudcore.light.far_ground import (
    far_ground_box,
    far_ground_colour,
    far_ground_level,
    far_ground_sun,
    in_shadow_map,
)
from cloudcore.light.ground_shadows import BakePlan, ground_shadow_frame, tile_keys
from cloudcore.light.light_shafts import SHAFT_STEPS
from cloudcore.light.sky_background import NIGHT_SKY, SkyBackground, ground_behind_the_air
from cloudcore.light.terrain_light import TerrainLight
from cloudcore.model.scene import Camera, Terrain
from cloudcore.scenes.limits import DRAWN_TERRAIN_KINDS
from cloudcore.world.camera import frustum_planes, pixel_rays
from cloudcore.world.terrain import ground_colours, highest_ground_m, lowest_ground_m
from cloudcore.world.terrain_tiles import (
    SKIRT_SIDES,
    TILE_FACES,
    TILE_VERTICES,
    TerrainTiles,
    grid_face_count,
    tile_faces,
)

#: the light shafts' depth of the terrain takes every 4th vertex of a tile's grid: the frames agree closely with the
#: whole grid's, whose triangles cost llvmpipe their setup (docs/atmosphere.md#light-shafts)
_COARSE_STRIDE = 4
#: a tile's vertices its coarse surface uses (into its grid's), and the surface's triangles (into these): the coarse
#: surfaces have a buffer of their own, as llvmpipe drew the same triangles slower from the whole grids' buffer,
#: whose index range spans all of a tile's vertices for the few the surface uses
#: (docs/atmosphere.md#the-shafts-cheaper-issue-52s-budget)
_COARSE_TILE_VERTICES, _COARSE_TILE_FACES = np.unique(tile_faces(_COARSE_STRIDE), return_inverse=True)
_COARSE_TILE_FACES = _COARSE_TILE_FACES.reshape(-1, 3)
#: the physical sky's picture's columns, about: read bilinearly from it, the sky is 65 to 86 dB from the sky a pixel
#: (8-bit sRGB, the sun's disc apart: it is drawn at the screen's), where each pixel's lookup cost llvmpipe more
#: than the fetch; its error follows the angle its pixels span, not the screen's (docs/atmosphere.md, "The sky at
#: a fraction of the resolution")
SKY_COLUMNS = 128


def sky_reduction(width: int) -> int:
    """Screen pixels a side of the sky's picture's pixel, for a frame `width` pixels wide: about `SKY_COLUMNS`
    columns, and the screen's own pixels on a screen narrower than that."""
    return max(1, round(width / SKY_COLUMNS))


#: the columns of rays at which `WorldPass` asks whether the far ground can be in the clouds' shadows (its rows
#: by the aspect): where none can, the sky's read does not branch into the map
FAR_GROUND_SHADOW_GRID = 32
#: the texture unit of the air's transmittance along the sky-view table's rows (sky.frag.glsl's FAR_GROUND)
_ROW_TRANSMITTANCE_UNIT = 8

#: metres the far ground's depth is taken below the terrain's lowest vertex (`WorldPass._ground_below_the_terrain`):
#: more than the depth buffer's step where the terrain meets the planet's level near the eye
_DEPTH_MARGIN_M = 20.0

#: a terrain vertex's attributes, 3 floats each: its position, the sun's light and the sky's (terrain.vert.glsl)
_VERTEX_ATTRIBUTES = 3


def terrain_vertex_light(normals, base_colour, light: TerrainLight) -> tuple[np.ndarray, np.ndarray]:
    """Linear RGB per vertex of unit `normals` and `base_colour` (one, or one a vertex): base * the sun's
    irradiance, and base * the rest (the sky's dome, the ground's bounce, the floor), which `light` gives each
    normal."""
    base = np.asarray(base_colour, dtype=np.float64)
    return base * light.sun_irradiance(normals), base * light.unshadowed_irradiance(normals)


class TerrainMesh:
    """The terrain's tiles on the GPU for one terrain and one light: uploaded again when the eye's move changes
    the tiles, drawn where a tile's box meets the view (their triangles gathered when those tiles change)."""

    def __init__(self, terrain: Terrain, light: TerrainLight, programs: ProgramCache):
        if terrain.kind not in DRAWN_TERRAIN_KINDS:  # the scene loader refuses these first (cloudcore.scenes.limits)
            raise ValueError(f"the GL prototype draws heightfield and heightmap terrain only, not {terrain.kind!r}")
        self._terrain, self._light = terrain, light
        self.tiles = TerrainTiles(terrain)
        self._programs = programs  # the world pass's
        self._coarse_in_view: np.ndarray | None = None  # the tiles whose coarse surfaces the coarse indices hold
        self._in_view: np.ndarray | None = None  # the tiles whose grids and skirts the indices hold
        self._shaded: np.ndarray | None = None  # which of them read the clouds' map
        self._far: np.ndarray | None = None  # which of them reach the air to the planet's ground
        # the indices' runs: ((whether they read the clouds' map, whether they reach that air), first triangle, count)
        self._runs: list[tuple[tuple[bool, bool], int, int]] = []
        self._eye: tuple[float, float, float] | None = None  # the eye the tiles were last chosen for
        # the clouds' shadow on the ground, baked for a steady map (`BakePlan`), and whether this frame reads it
        self.ground_shadows = GroundShadows(programs)
        self._bakes = BakePlan()
        self._read_baked = False
        # the tiles' vertices and triangles, their coarse surfaces' (the light shafts' depth: positions alone), and
        # the triangles of the grids under the clouds' map (the shadow's bake, from the tiles' vertices)
        self._buffers = [int(b) for b in GL.glGenBuffers(5)]
        self._vertex_array, self._coarse_vertex_array, self._bake_vertex_array = (
            int(a) for a in GL.glGenVertexArrays(3)
        )
        for vertex_array, (vertices, indices), attributes, stride in (
            (self._vertex_array, self._buffers[:2], _VERTEX_ATTRIBUTES, _VERTEX_ATTRIBUTES),
            (self._coarse_vertex_array, self._buffers[2:4], 1, 1),
            (self._bake_vertex_array, (self._buffers[0], self._buffers[4]), 1, _VERTEX_ATTRIBUTES),
        ):
            GL.glBindVertexArray(vertex_array)
            GL.glBindBuffer(GL.GL_ARRAY_BUFFER, vertices)
            for location in range(attributes):
                GL.glEnableVertexAttribArray(location)
                GL.glVertexAttribPointer(
                    location, 3, GL.GL_FLOAT, GL.GL_FALSE, 12 * stride, ctypes.c_void_p(12 * location)
                )
            GL.glBindBuffer(GL.GL_ELEMENT_ARRAY_BUFFER, indices)
        GL.glBindVertexArray(0)

    def _upload(self) -> None:
        tiles = self.tiles
        colours = ground_colours(self._terrain, tiles.positions, tiles.normals)
        sun, sky = terrain_vertex_light(tiles.normals, colours, self._light)
        coarse_vertices = tiles.positions.reshape(-1, TILE_VERTICES, 3)[:, _COARSE_TILE_VERTICES].reshape(-1, 3)
        for vertices, vertex_buffer in (
            (np.concatenate([tiles.positions, sun, sky], axis=1), self._buffers[0]),
            (coarse_vertices, self._buffers[2]),
        ):
            vertices = np.ascontiguousarray(vertices, dtype=np.float32)
            GL.glBindBuffer(GL.GL_ARRAY_BUFFER, vertex_buffer)
            GL.glBufferData(GL.GL_ARRAY_BUFFER, vertices.nbytes, vertices, GL.GL_STATIC_DRAW)
        self._in_view = self._coarse_in_view = None  # the triangles in view are gathered again

    def _follow(self, eye) -> None:
        """The tiles chosen for `eye`, uploaded where they changed; chosen once for an eye the frame's passes share
        (the shafts' depth, the shadow's bake, the draw), as choosing them is a walk of the quadtree in numpy."""
        eye = tuple(float(v) for v in eye)
        if eye == self._eye:
            return
        self._eye = eye
        if self.tiles.update(eye):
            self._upload()

    def _program(self, through_air: bool, shafts: bool, far_ground: bool, shadow_read: bool) -> int:
        """The terrain's program for its kind of tiles: seen `through_air`, less the light `shafts`, with the air to
        the planet's ground (`far_ground`: tiles reaching past `FAR_AIR_FROM`), reading the clouds' shadow."""
        defines = {
            "THROUGH_AIR": int(through_air),
            "LIGHT_SHAFTS": int(shafts),
            "FAR_GROUND": int(far_ground and through_air),
            "CLOUD_SHADOW_READ": int(shadow_read),
            "BAKED_SHADOW": int(shadow_read and self._read_baked),
        }
        return self._programs.program("terrain", defines)

    def draw(
        self,
        camera: Camera,
        view_projection: np.ndarray,
        air: AirVolume | None,
        shadows: CloudShadowMap | None,
        shafts: LightShaftPass | None = None,
        bind_far_air: Callable[[int], None] | None = None,
    ) -> None:
        """Draw the tiles in view for `camera` into the bound target, depth tested and written, seen through
        `air` (bound for `camera`'s eye) where there is one, past its volume through the air to the planet's
        ground that `bind_far_air(program)` binds where given (the sky's table: `WorldPass`), the sun's part in
        the clouds' `shadows` where given (read by the tiles under their map alone), less the light `shafts`
        (marched for this view) where given."""

        far_ground = air is not None and bind_far_air is not None

        def use(shadow_read: bool, far_air: bool) -> int:
            program = self._program(air is not None, shafts is not None, far_ground and far_air, shadow_read)
            GL.glUseProgram(program)
            if air is not None:
                air.bind(program)
                set_vec3(program, "eye_position", camera.position)
                if far_ground and far_air:
                    bind_far_air(program)
            if shadow_read:
                (self.ground_shadows if self._read_baked else shadows).bind(program)
            if shafts is not None:
                shafts.bind()
            return program

        far_from_m = FAR_AIR_FROM * MAX_DISTANCE_M if far_ground else None
        self._draw_tiles(use, camera, view_projection, None if shadows is None else shadows.space, far_from_m)

    def draw_depth(self, camera: Camera, view_projection: np.ndarray) -> None:
        """Draw the depth of the coarse surfaces of the tiles in view for `camera` alone into the bound target (the
        light shafts' march reads it at a fraction of the screen's resolution, where the tiles' triangles are
        mostly smaller than a pixel and cost llvmpipe their setup)."""
        program = self._programs.program("terrain_depth", {"THROUGH_AIR": 0, "CLOUD_SHADOW_READ": 0}, vertex="terrain")

        def use(_shadow_read: bool, _far_air: bool) -> int:
            GL.glUseProgram(program)
            return program

        self._draw_tiles(use, camera, view_projection, None, coarse=True)

    def bake_ground_shadows(self, camera: Camera, shadows: CloudShadowMap | None, steady: bool) -> None:
        """Bake the clouds' `shadows` (a `steady_map` where `steady`) on the tiles for `camera`'s eye under their map
        into the texture the tiles' pixels then read, as far as `BakePlan` says (those it holds are not baked
        again); leaves the texture's framebuffer bound where it bakes."""
        self._read_baked = False
        if shadows is None or shadows.space is None:
            return
        self._follow(camera.position)
        under = np.flatnonzero(self.tiles.under_the_clouds_map(shadows.space))
        step = self._bakes.step((shadows.made, shadows.space), tile_keys(self.tiles.tiles[under]), steady)
        self._read_baked = step.read_baked
        if not len(step.tiles):
            return
        terrain = self.tiles.terrain
        frame = ground_shadow_frame(
            shadows.space, lowest_ground_m(terrain), highest_ground_m(terrain), self.tiles.frame.half_side_m
        )
        baked = under[step.tiles]

        def draw_grids() -> None:
            grid = grid_face_count()
            faces = self.tiles.faces.reshape(len(self.tiles.tiles), len(TILE_FACES), 3)[baked, :grid]
            indices = np.ascontiguousarray(faces, dtype=np.uint32)
            GL.glBindVertexArray(self._bake_vertex_array)
            GL.glBufferData(GL.GL_ELEMENT_ARRAY_BUFFER, indices.nbytes, indices, GL.GL_DYNAMIC_DRAW)
            # their edges first, as lines: where a tile meets a finer one the two edges' rounding may leave a texel
            # between them that neither triangle covers (a lit speck in a shadow); the triangles then cover the rest
            GL.glPolygonMode(GL.GL_FRONT_AND_BACK, GL.GL_LINE)
            GL.glDrawElements(GL.GL_TRIANGLES, indices.size, GL.GL_UNSIGNED_INT, None)
            GL.glPolygonMode(GL.GL_FRONT_AND_BACK, GL.GL_FILL)
            GL.glDrawElements(GL.GL_TRIANGLES, indices.size, GL.GL_UNSIGNED_INT, None)
            GL.glBindVertexArray(0)

        self.ground_shadows.bake(frame, shadows, draw_grids, afresh=step.afresh)

    def _draw_tiles(
        self,
        use: Callable[[bool, bool], int],
        camera: Camera,
        view_projection: np.ndarray,
        space: LightSpace | None,
        far_from_m: float | None = None,
        coarse: bool = False,
    ) -> None:
        """Draw the tiles in view, depth tested and written, each with the program `use(shadow_read, far_air)` puts
        in use (its uniforms set): reading the clouds' map of light `space` for the tiles under it (`space` None: no
        tile), turning into the air to the planet's ground for the tiles reaching past `far_from_m` from the eye
        (None: no tile); their coarse surfaces where `coarse`."""
        self._follow(camera.position)
        in_view = np.flatnonzero(self.tiles.in_view(frustum_planes(view_projection)))
        if not len(in_view):
            return
        GL.glEnable(GL.GL_DEPTH_TEST)
        GL.glDepthFunc(GL.GL_LESS)
        GL.glDepthMask(GL.GL_TRUE)
        if coarse:
            set_matrix(use(False, False), "view_projection", view_projection)
            self._draw_coarse(in_view)
            return
        shaded = np.zeros(len(in_view), dtype=bool)
        if space is not None:
            shaded = self.tiles.under_the_clouds_map(space)[in_view]
        far = np.zeros(len(in_view), dtype=bool)
        if far_from_m is not None:
            far = self.tiles.reaching(camera.position, far_from_m)[in_view]
        GL.glBindVertexArray(self._vertex_array)
        if (
            self._in_view is None
            or not np.array_equal(self._in_view, in_view)
            or not np.array_equal(self._shaded, shaded)
            or not np.array_equal(self._far, far)
        ):
            self._gather(in_view, shaded, far)
        # back faces culled: the far sides of hills, hidden behind their near sides, and the skirts' sides that face
        # into their own tiles (`tile_faces`), which llvmpipe then does not set up or rasterise
        GL.glEnable(GL.GL_CULL_FACE)
        GL.glCullFace(GL.GL_BACK)
        programs: dict[tuple[bool, bool], int] = {}
        for kind, first, count in self._runs:
            if kind not in programs:
                programs[kind] = use(*kind)
                set_matrix(programs[kind], "view_projection", view_projection)
            else:
                GL.glUseProgram(programs[kind])
            offset = ctypes.c_void_p(3 * 4 * first)  # bytes of uint32 indices
            GL.glDrawElements(GL.GL_TRIANGLES, 3 * count, GL.GL_UNSIGNED_INT, offset)
        GL.glDisable(GL.GL_CULL_FACE)
        GL.glBindVertexArray(0)

    def _gather(self, in_view: np.ndarray, shaded: np.ndarray, far: np.ndarray) -> None:
        """Gather the triangles of the tiles `in_view` into the bound vertex array's indices, in runs each drawn in
        one call: the grids of the tiles `shaded` (under the clouds' map), the other tiles' grids, each of these
        groups split by whether the tile is `far` (reaching the air to the planet's ground), then their skirts on
        the sides that need one (`skirted_sides`) in the same groups, each group in the order the tiles come.
        Drawn as multi-draws of a range a tile and a side, llvmpipe set each range up as a draw of its own
        (docs/performance.md, "The terrain in two draws")."""
        grid = grid_face_count()
        faces = self.tiles.faces.reshape(len(self.tiles.tiles), len(TILE_FACES), 3)
        per_side = (len(TILE_FACES) - grid) // len(SKIRT_SIDES)
        runs, first = [], 0
        for grids in (True, False):
            for kind in itertools.product((True, False), (False, True)):
                tiles = in_view[(shaded == kind[0]) & (far == kind[1])]
                if grids:
                    triangles = faces[tiles, :grid]
                else:
                    tile, side = np.nonzero(self.tiles.skirts[tiles])
                    triangles = faces[tiles[tile][:, None], grid + side[:, None] * per_side + np.arange(per_side)]
                triangles = triangles.reshape(-1, 3)
                if len(triangles):
                    runs.append((kind, first, len(triangles), triangles))
                    first += len(triangles)
        indices = np.ascontiguousarray(np.concatenate([run[3] for run in runs]), dtype=np.uint32)
        GL.glBufferData(GL.GL_ELEMENT_ARRAY_BUFFER, indices.nbytes, indices, GL.GL_DYNAMIC_DRAW)
        self._in_view, self._shaded, self._far = in_view, shaded, far
        self._runs = [run[:3] for run in runs]

    def _draw_coarse(self, in_view: np.ndarray) -> None:
        """Draw the coarse surfaces of the tiles `in_view` in one call, none culled (at the march's resolution
        llvmpipe's cost per draw, a draw per tile, exceeded the triangles' own); their triangles gathered into the
        coarse index buffer when the tiles in view change."""
        GL.glBindVertexArray(self._coarse_vertex_array)
        if self._coarse_in_view is None or not np.array_equal(self._coarse_in_view, in_view):
            starts = in_view * len(_COARSE_TILE_VERTICES)
            faces = np.ascontiguousarray(_COARSE_TILE_FACES[None, :, :] + starts[:, None, None], dtype=np.uint32)
            GL.glBufferData(GL.GL_ELEMENT_ARRAY_BUFFER, faces.nbytes, faces, GL.GL_DYNAMIC_DRAW)
            self._coarse_in_view = in_view
        GL.glDrawElements(GL.GL_TRIANGLES, 3 * len(in_view) * len(_COARSE_TILE_FACES), GL.GL_UNSIGNED_INT, None)
        GL.glBindVertexArray(0)

    def lowest_m(self) -> float:
        """The lowest height of the tiles drawn last (their skirts' included), 0 before any."""
        boxes = self.tiles.boxes
        return float(boxes[:, 0, 1].min()) if len(boxes) else 0.0

    def close(self) -> None:
        GL.glDeleteBuffers(len(self._buffers), self._buffers)
        GL.glDeleteVertexArrays(3, [self._vertex_array, self._coarse_vertex_array, self._bake_vertex_array])
        self.ground_shadows.close()


class WorldPass:
    """Terrain and sky for one terrain and one lighting; rebuild it when either changes."""

    def __init__(
        self,
        terrain: Terrain | None,
        light: TerrainLight,
        sky: SkyBackground,
        air_for: Callable[[SkyBackground, np.ndarray], AirBetween | None] = air_between,
        sky_for: Callable[[SkyBackground, np.ndarray], SkyBackground] = SkyBackground.seen_from,
        shaft_steps: int = SHAFT_STEPS,
        shaft_reduction: int | None = None,
        programs: ProgramCache | None = None,
    ):
        """`air_for(sky, eye)`: the air an eye sees through (`air_between`, or the editor's `LiveAir`), and
        `sky_for(sky, eye)` the sky it sees (`SkyBackground.seen_from`, or `LiveAir.sky_seen_from`); the light
        shafts marched by `shaft_steps` at a pixel for each `shaft_reduction`-square block of the screen's (None:
        `light_shafts.shaft_reduction`'s); the programs from `programs` (the frame's, kept across the world passes a
        new light makes again: the caller closes it), else its own."""
        self._own_programs = programs is None
        self._programs = ProgramCache() if programs is None else programs
        self._shaft_quality = shaft_steps, shaft_reduction
        self._sky, self._air_for, self._sky_for = sky, air_for, sky_for
        # the sky-view table and the air's transmittance along its rows
        self._sky_view_textures = [int(t) for t in GL.glGenTextures(2)] if sky.physical else None
        # the planet's ground past the terrain, drawn by the physical sky below the horizon (none without a terrain:
        # the air at the horizon is drawn there), as `ground_behind_the_air` adds it to the table's air
        self._far_ground = (
            ground_behind_the_air(far_ground_colour(terrain, light)) if sky.physical and terrain is not None else None
        )
        #: (its sun's part, its level) where the clouds' shadows fall on it (sky_read.frag.glsl's FAR_GROUND_SHADOWS)
        self._far_ground_shadowed = (
            None if self._far_ground is None else (far_ground_sun(terrain, light), far_ground_level(terrain))
        )
        self._uploaded_view = None  # the sky-view table the texture holds
        # core profile draws nothing without a vertex array, even one with no attributes
        self._fullscreen_vertex_array = GL.glGenVertexArrays(1)
        self._terrain = TerrainMesh(terrain, light, self._programs) if terrain is not None else None
        # the air's volume under the physical sky (the cloud pass reads it too: `air_volume`)
        self._air_volume = AirVolume() if sky.physical else None
        self._shafts: LightShaftPass | None = None  # built when a frame first has them
        # the physical sky at a fraction of the screen's resolution, and the program that reads it at its own
        self._sky_target: TextureTarget | None = None

    def draw(
        self,
        context: HeadlessContext,
        camera: Camera,
        view: np.ndarray,
        projection: np.ndarray,
        *,
        antialiased: bool = False,
        through_air: bool = True,
        shadows: CloudShadowMap | None = None,
        steady_shadows: bool = True,
        light_shafts: bool = False,
        draw_cloud_depth: Callable[[tuple[int, int]], None] | None = None,
    ) -> LightShaftPass | None:
        """Fill the render target for `camera` seen through `view` and `projection`: terrain colour and depth where
        there is terrain, sky elsewhere (both multisampled 4x when `antialiased`, the terrain seen through the air
        under the physical sky when `through_air`, its sun's part in the clouds' `shadows` where given (baked on the
        ground where they are `steady_shadows`: `ground_shadows.steady_map`), and with
        `light_shafts` the air in their shadow darkened where there are shadows and air, its rays marched up to
        the clouds' nearest depth that `draw_cloud_depth(size)` draws at the march's size where given: Yusov's
        cut).  Returns the light shafts' pass where it marched them, for the clouds to read; else None."""
        view_projection = projection @ view
        sky = self._sky_for(self._sky, camera.position)
        if sky.physical and sky.view is not self._uploaded_view:
            _upload_sky_view(self._sky_view_textures, sky)
            self._uploaded_view = sky.view
        air = None
        if self._air_volume is not None and through_air:
            self._air_volume.upload(self._air_for(self._sky, camera.position))
            air = self._air_volume
        # the planet's ground under the terrain, where the shafts' rays end and the sky's read pass writes its depth
        below = None if self._far_ground is None else self._ground_below_the_terrain(sky, camera)
        shafts = None
        if light_shafts and air is not None and shadows is not None and shadows.space is not None:
            shafts = self._light_shafts()
            terrain = self._terrain
            shafts.march(
                (context.width, context.height),
                None if terrain is None else lambda: terrain.draw_depth(camera, view_projection),
                camera,
                view,
                projection,
                air,
                shadows,
                sky.lowest_up(),
                below,
                draw_cloud_depth,
            )
        if sky.physical:
            self._draw_sky_picture(sky, camera, view_projection, (context.width, context.height), shafts)
        if self._terrain is not None:
            self._terrain.bake_ground_shadows(camera, shadows, steady_shadows)
        framebuffer = context.multisampled_target() if antialiased else context.framebuffer
        GL.glBindFramebuffer(GL.GL_FRAMEBUFFER, framebuffer)
        GL.glViewport(0, 0, context.width, context.height)
        GL.glDepthMask(GL.GL_TRUE)
        GL.glClearDepth(1.0)
        GL.glClear(GL.GL_DEPTH_BUFFER_BIT)  # every colour is drawn: the terrain's, else the sky's
        GL.glDisable(GL.GL_BLEND)
        GL.glDisable(GL.GL_CULL_FACE)  # the sky's triangle is not culled (the terrain's tiles cull their own)
        if self._terrain is not None:
            far_air = None if self._far_ground is None else lambda program: self._set_sky_view_uniforms(program, sky)
            self._terrain.draw(camera, view_projection, air, shadows, shafts, far_air)
        self._draw_sky(sky, camera, view, projection, (context.width, context.height), below, shadows)
        if antialiased:
            context.resolve_multisampled_target()
        context.bind_target()
        return shafts

    def _draw_sky_picture(
        self, sky: SkyBackground, camera: Camera, view_projection: np.ndarray, size: tuple[int, int], shafts
    ) -> None:
        """The physical sky, less the light `shafts` take, into the sky's target at `sky_reduction`'s fraction of
        the screen's resolution, over every pixel whatever is drawn in front (the full-size pass reads it)."""
        reduction = sky_reduction(size[0])
        wanted = (-(-size[0] // reduction), -(-size[1] // reduction))
        if self._sky_target is None or (self._sky_target.width, self._sky_target.height) != wanted:
            if self._sky_target is not None:
                self._sky_target.close()
            self._sky_target = TextureTarget(*wanted, GL.GL_RGBA16F)
        self._sky_target.bind()
        program = self._sky_program(shafts is not None)
        GL.glUseProgram(program)
        if shafts is not None:
            shafts.bind()
        set_matrix(program, "inverse_view_projection", np.linalg.inv(view_projection))
        self._set_sky_uniforms(program, sky, camera, size[1])
        GL.glDisable(GL.GL_DEPTH_TEST)
        GL.glDisable(GL.GL_BLEND)
        GL.glBindVertexArray(self._fullscreen_vertex_array)
        GL.glDrawArrays(GL.GL_TRIANGLES, 0, 3)
        GL.glBindVertexArray(0)

    def _draw_sky(
        self,
        sky: SkyBackground,
        camera: Camera,
        view: np.ndarray,
        projection: np.ndarray,
        size: tuple[int, int],
        below: tuple[float, float] | None,
        shadows: CloudShadowMap | None = None,
    ) -> None:
        """The sky behind the terrain drawn into the bound target: the physical sky's picture read (with the sun's
        disc added in its box; the ground past the terrain, `below` (`_ground_below_the_terrain`), given its
        depth and its sun's part the clouds' `shadows`), or the gradient."""
        view_projection = projection @ view
        inverse_view_projection = np.linalg.inv(view_projection)
        GL.glEnable(GL.GL_DEPTH_TEST)
        GL.glDepthFunc(GL.GL_LEQUAL)
        GL.glDepthMask(GL.GL_FALSE)
        GL.glBindVertexArray(self._fullscreen_vertex_array)
        if sky.physical:
            self._use_sky_read(False, False, sky, camera, view, projection, below, shadows)
        else:
            program = self._sky_program(False)
            GL.glUseProgram(program)
            set_matrix(program, "inverse_view_projection", inverse_view_projection)
            self._set_sky_uniforms(program, sky, camera, size[1])
        GL.glDrawArrays(GL.GL_TRIANGLES, 0, 3)
        ground_box = None
        if sky.physical and self._far_ground is not None:
            ground_box = far_ground_box(
                inverse_view_projection, camera.position, size, below, self._terrain_half_side_m()
            )
        if ground_box is not None:
            # the ground past the terrain takes its depth, so that clouds behind it are hidden; drawn again in the
            # box where it may be seen alone, as a pass that writes its depth is shaded on every pixel it covers;
            # its sun's part in the clouds' shadows where any of it can be in them
            shadowed = self._far_ground_in_shadows(camera, size, shadows)
            self._use_sky_read(True, shadowed, sky, camera, view, projection, below, shadows)
            GL.glDepthMask(GL.GL_TRUE)
            GL.glEnable(GL.GL_SCISSOR_TEST)
            GL.glScissor(*ground_box)
            GL.glDrawArrays(GL.GL_TRIANGLES, 0, 3)
            GL.glDisable(GL.GL_SCISSOR_TEST)
        GL.glDepthMask(GL.GL_FALSE)
        box = sun_box(sky, camera, view_projection, size) if sky.physical else None
        if box is not None:  # the sun's disc added where it can be
            disc = self._sky_program(False, sun_disc=True)
            GL.glUseProgram(disc)
            set_matrix(disc, "inverse_view_projection", inverse_view_projection)
            self._set_sky_uniforms(disc, sky, camera, size[1])
            GL.glEnable(GL.GL_BLEND)
            GL.glBlendFunc(GL.GL_ONE, GL.GL_ONE)
            GL.glEnable(GL.GL_SCISSOR_TEST)
            GL.glScissor(*box)
            GL.glDrawArrays(GL.GL_TRIANGLES, 0, 3)
            GL.glDisable(GL.GL_SCISSOR_TEST)
            GL.glDisable(GL.GL_BLEND)
        GL.glBindVertexArray(0)
        GL.glDepthMask(GL.GL_TRUE)
        GL.glDepthFunc(GL.GL_LESS)

    def _sky_read_program(self, ground_depth: bool, shadowed: bool) -> int:
        """The program that reads the sky's picture; writing the far ground's depth where `ground_depth`, its sun's
        part in the clouds' shadows where `shadowed`."""
        defines = {
            "DEPTH": 1.0,
            "FAR_GROUND": int(ground_depth),
            "VIEW_RAY": int(ground_depth),
            "FAR_GROUND_SHADOWS": int(shadowed),
        }
        return self._programs.program("sky_read", defines, vertex="world")

    def _terrain_half_side_m(self) -> float:
        """The half side of the square the terrain's tiles are drawn to, about the origin."""
        return self._terrain.tiles.frame.half_side_m

    def _use_sky_read(
        self,
        ground_depth: bool,
        shadowed: bool,
        sky: SkyBackground,
        camera: Camera,
        view: np.ndarray,
        projection: np.ndarray,
        below: tuple[float, float] | None,
        shadows: CloudShadowMap | None,
    ) -> None:
        """Use the program that reads the sky's picture (writing the far ground's depth where `ground_depth`, its
        sun's part in the clouds' `shadows` where `shadowed`), its uniforms set."""
        program = self._sky_read_program(ground_depth, shadowed)
        GL.glUseProgram(program)
        GL.glActiveTexture(GL.GL_TEXTURE2)
        GL.glBindTexture(GL.GL_TEXTURE_2D, self._sky_target.texture)
        GL.glActiveTexture(GL.GL_TEXTURE0)
        if ground_depth:
            set_matrix(program, "inverse_view_projection", np.linalg.inv(projection @ view))
            GL.glUniform2f(GL.glGetUniformLocation(program, "planet_ground"), *below)
            set_vec3(program, "view_forward", -view[2, :3])
            GL.glUniform2f(GL.glGetUniformLocation(program, "depth_terms"), projection[2, 2], projection[2, 3])
        if shadowed:
            shadows.bind(program)
            self._set_sky_view_uniforms(program, sky)
            sun_part, level = self._far_ground_shadowed
            set_vec3(program, "far_ground_sun", sun_part)
            set_vec3(program, "eye", camera.position)
            GL.glUniform1f(GL.glGetUniformLocation(program, "far_ground_y"), level)

    def _far_ground_in_shadows(self, camera: Camera, size: tuple[int, int], shadows: CloudShadowMap | None) -> bool:
        """Whether the far ground can be in the clouds' `shadows` anywhere on the screen (`in_shadow_map` at a
        coarse grid of rays): the sky's read branches into the map only then."""
        if shadows is None or shadows.space is None:
            return False
        columns = FAR_GROUND_SHADOW_GRID
        rows = max(1, round(columns * size[1] / size[0]))
        rays = pixel_rays(camera, columns, rows)
        level = self._far_ground_shadowed[1]
        return bool(in_shadow_map(camera.position, rays, shadows.space, self._terrain_half_side_m(), level).any())

    def _sky_program(self, shafts: bool, sun_disc: bool = False) -> int:
        """The sky's program, less the light `shafts` take where asked; the sun's disc alone for `sun_disc`."""
        # at the far plane (the window depth 1), drawn where the depth is still the clear's
        defines = {
            "PHYSICAL_SKY": int(self._sky.physical),
            "FAR_GROUND": int(self._far_ground is not None),
            "LIGHT_SHAFTS": int(shafts),
            "SUN_DISC": int(sun_disc),
            "VIEW_RAY": 1,
            "DEPTH": 1.0,
        }
        return self._programs.program("sky", defines, vertex="world")

    def _ground_below_the_terrain(self, sky: SkyBackground, camera: Camera) -> tuple[float, float]:
        """(the eye's altitude over it, its radius) of the planet's ground lowered under every vertex of the terrain
        drawn (and the sea's level) by `_DEPTH_MARGIN_M`: the far ground's depth is that sphere's, which the terrain
        always stands in front of (the sphere curves away under the level through its lowest point), so the sky's
        read pass, depth tested against the terrain, never draws over it; the light shafts' march ends its rays past
        the terrain there too."""
        params = sky.view.tables.params
        lowest = self._terrain.lowest_m() if self._terrain is not None else 0.0
        level = min(0.0, sky.origin_altitude_m + lowest) - _DEPTH_MARGIN_M
        return sky.eye_altitude_m(camera.position) - level, params.bottom_radius_m + level

    def _light_shafts(self) -> LightShaftPass:
        if self._shafts is None:
            self._shafts = LightShaftPass(*self._shaft_quality, programs=self._programs)
        return self._shafts

    @property
    def ground_shadows(self) -> GroundShadows | None:
        """The clouds' shadow baked on the terrain's ground (what the terrain's pixels read while the map is held);
        None without a terrain."""
        return None if self._terrain is None else self._terrain.ground_shadows

    @property
    def light_shafts(self) -> LightShaftPass | None:
        """The light shafts' pass, once a frame has drawn them (tests read its march)."""
        return self._shafts

    def _set_sky_uniforms(self, program: int, sky: SkyBackground, camera: Camera, viewport_height: int) -> None:
        if not sky.physical:
            set_vec3(program, "zenith_colour", sky.zenith)
            set_vec3(program, "horizon_colour", sky.horizon)
            return
        self._set_sky_view_uniforms(program, sky)
        set_vec3(program, "sun_disc_scale", sky.sun_disc_scale())
        GL.glUniform1f(
            GL.glGetUniformLocation(program, "pixel_angle"),
            float(np.radians(camera.fov_y_deg) / max(viewport_height, 1)),
        )

    def _set_sky_view_uniforms(self, program: int, sky: SkyBackground) -> None:
        """Bind the sky-view table of `sky` for `program` (shaders/sky_view.glsl), with the far ground's where there
        is one."""
        params = sky.view.tables.params
        r = eye_radius(params, sky.view.altitude_m)
        _, zenith_horizon = horizon_angles(params, r)
        GL.glActiveTexture(GL.GL_TEXTURE1)
        GL.glBindTexture(GL.GL_TEXTURE_2D, self._sky_view_textures[0])
        if self._far_ground is not None:
            GL.glActiveTexture(GL.GL_TEXTURE0 + _ROW_TRANSMITTANCE_UNIT)
            GL.glBindTexture(GL.GL_TEXTURE_2D, self._sky_view_textures[1])
            set_vec3(program, "far_ground", self._far_ground)
            set_vec3(program, "night_sky", NIGHT_SKY)
        height, width = sky.view.table.shape[:2]
        GL.glUniform2f(GL.glGetUniformLocation(program, "sky_view_size"), float(width), float(height))
        GL.glUniform1f(GL.glGetUniformLocation(program, "zenith_horizon_angle"), float(zenith_horizon))
        GL.glUniform1f(
            GL.glGetUniformLocation(program, "horizon_cosine"), float(horizon_cosine(r, params.bottom_radius_m))
        )
        set_vec3(program, "sun_direction", sky.view.sun_direction)
        GL.glActiveTexture(GL.GL_TEXTURE0)

    @property
    def air_volume(self) -> AirVolume | None:
        """The air's volume as the last `draw` uploaded it, for its eye; None under the gradient sky."""
        return self._air_volume

    def close(self) -> None:
        """Free the GL objects (the context must be current)."""
        if self._sky_view_textures is not None:
            GL.glDeleteTextures(self._sky_view_textures)
        if self._air_volume is not None:
            self._air_volume.close()
        if self._terrain is not None:
            self._terrain.close()
        if self._shafts is not None:
            self._shafts.close()
        if self._own_programs:
            self._programs.close()
        if self._sky_target is not None:
            self._sky_target.close()
        GL.glDeleteVertexArrays(1, [self._fullscreen_vertex_array])


def sun_box(
    sky: SkyBackground, camera: Camera, view_projection: np.ndarray, size: tuple[int, int]
) -> tuple[int, int, int, int] | None:
    """The window's box (x, y from the bottom left, width, height) holding every pixel the sun's disc may touch
    for `camera` seen through `view_projection` on a target of `size`: the disc and two pixels of rim around it,
    its edge projected at 16 points; None where none of it is on the screen or it is behind the eye."""
    sun = sky.view.sun_direction
    reach = SUN_ANGULAR_RADIUS + 2.0 * np.radians(camera.fov_y_deg) / max(size[1], 1)
    # two unit vectors across the sun's direction, and the rim's points at `reach` from it
    side = np.cross(sun, [0.0, 1.0, 0.0] if abs(sun[1]) < 0.9 else [1.0, 0.0, 0.0])
    side /= np.linalg.norm(side)
    other = np.cross(sun, side)
    turns = np.linspace(0.0, 2.0 * np.pi, 16, endpoint=False)[:, None]
    rim = np.cos(reach) * sun + np.sin(reach) * (np.cos(turns) * side + np.sin(turns) * other)
    clip = np.column_stack([rim + np.asarray(camera.position, dtype=np.float64), np.ones(len(rim))]) @ view_projection.T
    if np.any(clip[:, 3] <= 0.0):
        return None
    pixels = (0.5 * (clip[:, :2] / clip[:, 3:4]) + 0.5) * np.asarray(size, dtype=np.float64)
    low = np.maximum(np.floor(pixels.min(axis=0)) - 1.0, 0.0)
    high = np.minimum(np.ceil(pixels.max(axis=0)) + 1.0, size)
    if np.any(high <= low):
        return None
    return int(low[0]), int(low[1]), int(high[0] - low[0]), int(high[1] - low[1])


def _upload_sky_view(textures: list[int], sky: SkyBackground) -> None:
    """Fill `textures` with the sky-view table of `sky` in the renderer's values and the air's transmittance along
    its rows (a column), as floats, sampled linearly and clamped to their edge texels as
    `cloudcore.atmosphere.table_sampling` reads them."""
    # row 0 of a table is v's first texel: GL's first row, so the shader reads it with the numpy side's (u, v)
    for texture, table in zip(textures, (sky.table(), sky.view.row_transmittance[:, None, :]), strict=True):
        GL.glBindTexture(GL.GL_TEXTURE_2D, texture)
        linear_filtering(GL.GL_TEXTURE_2D)
        pixels = np.ascontiguousarray(table, dtype=np.float32)
        height, width = pixels.shape[:2]
        GL.glTexImage2D(GL.GL_TEXTURE_2D, 0, GL.GL_RGB32F, width, height, 0, GL.GL_RGB, GL.GL_FLOAT, pixels)
    GL.glBindTexture(GL.GL_TEXTURE_2D, 0)

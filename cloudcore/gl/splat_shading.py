"""Eye shading: each particle of a draw coloured for the eye (Harris eq. 5) into the instances the raster draws.

`splat_shade.comp.glsl` reads the resident particles (`cloudcore.gl.splat_residency`) in a draw's order and
writes per particle its four corners and colours (`INSTANCE_BYTES`), relative to the draw's eye; a selection's
order is first chosen and sorted on the GPU (`cloudcore.gl.splat_order`).  A pass's draws are shaded
together before any is drawn (`shade_ahead`), in one upload of the CPU's orders and one dispatch per run of
draws of the same particles, scene time and shader variant.
"""

from __future__ import annotations

import numpy as np
from OpenGL import GL

from cloudcore.gl.air_volume import AirVolume
from cloudcore.gl.light_shafts import FrameShafts
from cloudcore.gl.programs import build_compute_program, dispatch, uniform_locations
from cloudcore.gl.splat_order import GpuSplatOrder
from cloudcore.gl.splat_residency import ResidentParticles
from cloudcore.gl.storage import bind_storage, copy_buffer, store
from cloudcore.light.phase import PHASE_NAMES
from cloudcore.light.splat_look import SplatLook
from cloudcore.particles.batch import SplatBatch, SplatSelection
from cloudcore.particles.buffer import FADE_END_RADII, FADE_START_RADII, ParticleBuffer
from cloudcore.scenes.limits import MAX_LIGHTS

#: per particle, written by the compute shader: four corners and four colours (vec4 each)
INSTANCE_BYTES = 8 * 16
#: per particle beside its instance, for a look other than plain (`cloudcore.light.splat_look`): the sun's part of
#: its colour and its own optical depth, the sun's direction and its index (vec4 each)
TERMS_BYTES = 2 * 16
(
    _PARTICLES_BINDING,
    _FORMATION_BINDING,
    _ORDER_BINDING,
    INSTANCES_BINDING,  # where splat.vert.glsl reads the instances too
    _CLOUDS_BINDING,
    _FACING_BINDING,
    _PROFILES_BINDING,
    _BATCHES_BINDING,
    _RETURNED_BINDING,
    TERMS_BINDING,  # where splat.vert.glsl reads the pixel terms too
) = range(10)
#: floats of splat_shade.comp.glsl's `Batch`: first slot and count (as uints), eye, image plane's right and up
_BATCH_FLOATS = 16
#: the compute shader's local_size_x
_SHADE_GROUP = 64
#: a batch's instances start at a multiple of this many slots: 256 bytes, the largest offset alignment of a
#: storage buffer range GL allows, so that any batch's can be bound alone
_SLOT_ALIGNMENT = 256 // INSTANCE_BYTES
#: splat_shade.comp.glsl's optional code, in the order of a variant's key: sprites that do not lie in the
#: image plane, Wang's artist colours, Yusov's eye-pass profiles, the air between the eye and each particle, the
#: light a lit face sent back (`cloudcore.particles.buffer.ParticleBuffer.returned`), the terms a splat is shaded
#: by per pixel (`SplatLook`, when not plain), the light shafts' share taken off that air (the cloud pass's
#: batches, under the shafts alone)
_SHADE_FEATURES = ("FACING", "ARTIST", "PROFILES", "AIR", "RETURNED", "PIXEL_TERMS", "LIGHT_SHAFTS")
#: what a draw after shading waits for: the instances (and a selection's indirect command)
_SHADED_BARRIERS = GL.GL_SHADER_STORAGE_BARRIER_BIT | GL.GL_COMMAND_BARRIER_BIT


def _slots(count: int) -> int:
    """Slots a batch of `count` particles takes, its start aligned."""
    return -(-count // _SLOT_ALIGNMENT) * _SLOT_ALIGNMENT


class SplatShading:
    """Shades draws' particles for their eyes into one instance buffer, and keeps where each draw's are."""

    def __init__(self, resident: ResidentParticles, order: GpuSplatOrder):
        self._resident, self._order = resident, order
        (self.instance_buffer, self.order_buffer, self._batch_buffer, self.terms_buffer) = self._buffers = (
            GL.glGenBuffers(4)
        )
        #: how the raster shades the splats per pixel: other than plain, each slot's pixel terms are written too
        self.look = SplatLook()
        #: the frame's air (`cloudcore.gl.air_volume`), uploaded for its eye, which batches `through_air` take;
        #: None: no air (the gradient sky)
        self.air: AirVolume | None = None
        #: the frame's light shafts (`FrameShafts`), whose share of the air in front of a particle its air loses
        #: in the batches `through_air`, set for the cloud pass alone (a ring's segments are seen from the ring's
        #: eye); None: no shafts
        self.shafts: FrameShafts | None = None
        #: the compute shader's variants by the features a batch has (`_SHADE_FEATURES`), made when first
        #: needed: (program, its uniforms' locations, the particles its light uniforms are of)
        self._programs: dict[tuple, list] = {}
        self._instance_capacity = 0  # slots
        #: the batches the pass shaded ahead (`shade_ahead`): id -> (first slot, the view they were shaded
        #: for, the batch, kept so that its id stays its own); and the slots they fill, after which any
        #: other batch is shaded as it is drawn
        self._shaded: dict[int, tuple[int, np.ndarray, SplatBatch]] = {}
        self._slots_ahead = 0

    def shade_ahead(self, batches_and_views) -> None:
        """Shade the (batch, view) pairs a pass will draw, one after the other before any of its draws, and
        forget those shaded before: `draw` and `shade` then find them shaded.

        The compute shader's results need a memory barrier before a draw reads them, and llvmpipe makes
        each barrier a glFinish: shaded draw by draw, every batch waited for the draws before it.
        """
        self._shaded, self._slots_ahead = {}, 0
        self._order.begin_pass()
        batches_and_views = [(batch, view) for batch, view in batches_and_views if batch.slots]
        if not batches_and_views:
            return
        slots = sum(_slots(batch.slots) for batch, _ in batches_and_views)
        self._reserve(slots, keep=False)
        firsts = self._shade_all(batches_and_views, 0)
        for (batch, view), first in zip(batches_and_views, firsts):
            self._shaded[id(batch)] = (first, np.array(view, dtype=np.float64), batch)
        self._slots_ahead = slots
        GL.glMemoryBarrier(_SHADED_BARRIERS)

    def shaded_ahead(self, batch: SplatBatch | SplatSelection, view: np.ndarray) -> int | None:
        """The first slot of `batch` where `shade_ahead` shaded it for `view`; None where it did not."""
        shaded = self._shaded.get(id(batch))
        return shaded[0] if shaded is not None and np.array_equal(shaded[1], view) else None

    def shade(self, batch: SplatBatch, view: np.ndarray) -> tuple[int, int]:
        """(the storage buffer holding the batch's quads and colours for its eye, in its order, the slot of
        its first): those `shade_ahead` made, else shaded now after them (the volume-aware blending pass
        reads them too)."""
        first = self.shaded_ahead(batch, view)
        if first is not None:
            return self.instance_buffer, first
        self._reserve(self._slots_ahead + _slots(batch.slots), keep=True)
        self._shade_all([(batch, view)], self._slots_ahead)
        GL.glMemoryBarrier(_SHADED_BARRIERS)
        return self.instance_buffer, self._slots_ahead

    def _reserve(self, slots: int, keep: bool) -> None:
        """Room for `slots` instances (and their order), growing geometrically; `keep`: with the instances
        shaded so far, which draws to come may still read."""
        if slots <= self._instance_capacity:
            return
        capacity = max(slots, 2 * self._instance_capacity)
        for buffer, slot_bytes in ((self.instance_buffer, INSTANCE_BYTES), (self.terms_buffer, TERMS_BYTES)):
            kept = self._slots_ahead * slot_bytes if keep else 0
            # the buffer keeps its name (draws and the volume pass bind it by name): what is kept goes through a
            # scratch copy while it is reallocated; growing happens a few times a session
            scratch = GL.glGenBuffers(1) if kept else None
            if kept:
                copy_buffer(buffer, scratch, kept, allocate=True)
            GL.glBindBuffer(GL.GL_SHADER_STORAGE_BUFFER, buffer)
            GL.glBufferData(GL.GL_SHADER_STORAGE_BUFFER, capacity * slot_bytes, None, GL.GL_DYNAMIC_COPY)
            if kept:
                copy_buffer(scratch, buffer, kept, allocate=False)
                GL.glDeleteBuffers(1, [scratch])
        GL.glBindBuffer(GL.GL_SHADER_STORAGE_BUFFER, self.order_buffer)
        GL.glBufferData(GL.GL_SHADER_STORAGE_BUFFER, capacity * 4, None, GL.GL_STREAM_DRAW)
        GL.glBindBuffer(GL.GL_SHADER_STORAGE_BUFFER, 0)
        self._instance_capacity = capacity

    def _shade_all(self, batches_and_views, first: int) -> list[int]:
        """Shade the (batch, view) pairs (room reserved) into the slots from `first` on, each batch's start
        aligned; returns each one's first slot.  All the CPU's orders go up in one upload, and each run of
        batches with the same particles, scene time and shader variant is one dispatch."""
        runs: dict[tuple, list] = {}  # key -> [[batch, view, first slot]], slots contiguous within a run
        for batch, view in batches_and_views:
            runs.setdefault((id(batch.particles), batch.time_s, self._features(batch)), []).append([batch, view])
        firsts, end = {}, first
        for run in runs.values():
            for entry in run:
                entry.append(end)
                firsts[id(entry[0])] = end
                end += _slots(entry[0].slots)
        orders = np.zeros(end - first, dtype=np.uint32)
        for run in runs.values():
            for batch, _, slot in run:
                if isinstance(batch, SplatBatch):
                    orders[slot - first : slot - first + len(batch)] = batch.order
        GL.glBindBuffer(GL.GL_SHADER_STORAGE_BUFFER, self.order_buffer)
        GL.glBufferSubData(GL.GL_SHADER_STORAGE_BUFFER, first * 4, orders.nbytes, orders)
        GL.glBindBuffer(GL.GL_SHADER_STORAGE_BUFFER, 0)
        for (_, _, features), run in runs.items():
            self._dispatch(run, features)
        return [firsts[id(batch)] for batch, _ in batches_and_views]

    def _dispatch(self, run: list, features: tuple) -> None:
        """Shade a run of (batch, view, first slot), their order uploaded, in one dispatch of the variant with
        `features` (selections are chosen and sorted first)."""
        particles, time_s = run[0][0].particles, run[0][0].time_s
        self._resident.hold(particles)
        self._resident.hold_formation(particles, time_s)
        for batch, _, slot in run:
            if isinstance(batch, SplatSelection):
                self._order.select(batch, slot, self.order_buffer)
        rows = []  # (first slot, slots, eye, view): a batch's, a cell's of a selection of cells
        for batch, view, slot in run:
            if isinstance(batch, SplatSelection) and batch.cells is not None:
                firsts, held = batch.cell_slots()
                rows.extend((slot + first, count, batch.eye, cell) for first, count, cell in zip(firsts, held, view))
            else:
                rows.append((slot, batch.slots, batch.eye, view))
        table = np.zeros((len(rows), _BATCH_FLOATS), dtype=np.float32)
        slots = table.view(np.uint32)
        for row, (slot, count, eye, view) in enumerate(rows):
            slots[row, 0:2] = slot, count
            table[row, 4:7], table[row, 8:11], table[row, 12:15] = eye, view[0, :3], view[1, :3]
        store(self._batch_buffer, table, GL.GL_STREAM_DRAW)
        bind_storage(
            (_PARTICLES_BINDING, self._resident.particle_buffer),
            (_FORMATION_BINDING, self._resident.formation_buffer),
            (_ORDER_BINDING, self.order_buffer),
            (INSTANCES_BINDING, self.instance_buffer),
            (_CLOUDS_BINDING, self._resident.cloud_buffer),
            (_FACING_BINDING, self._resident.facing_buffer),
            (_PROFILES_BINDING, self._resident.profile_buffer),
            (_BATCHES_BINDING, self._batch_buffer),
        )
        if features[_SHADE_FEATURES.index("RETURNED")]:
            # binding 8 is others' between dispatches (the splats' cells, the tiles' occupancy): bound only here
            bind_storage((_RETURNED_BINDING, self._resident.returned_buffer))
        if features[_SHADE_FEATURES.index("PIXEL_TERMS")]:
            bind_storage((TERMS_BINDING, self.terms_buffer))
        program, uniforms = self._shade_program(features)
        first, end = run[0][2], run[-1][2] + run[-1][0].slots
        GL.glUseProgram(program)
        if features[_SHADE_FEATURES.index("AIR")]:
            self.air.bind(program)
        if features[_SHADE_FEATURES.index("LIGHT_SHAFTS")]:
            self.shafts.bind(program)
        GL.glUniform1ui(uniforms["first"], first)
        GL.glUniform1ui(uniforms["slot_count"], end - first)
        GL.glUniform1ui(uniforms["batch_count"], len(rows))
        dispatch(-(-(end - first) // _SHADE_GROUP))

    def _features(self, batch: SplatBatch | SplatSelection) -> tuple[bool, ...]:
        """The shader features (`_SHADE_FEATURES`) `batch`'s particles need."""
        bits = self._resident.feature_bits(batch)
        air = batch.through_air and self.air is not None
        shafts = air and self.shafts is not None
        returning = self._resident.returning
        return bool(bits & 1), bool(bits & 2), self._resident.profiled, air, returning, not self.look.plain, shafts

    def _shade_program(self, features: tuple[bool, ...]) -> tuple[int, dict]:
        """The compute shader variant with `features`, its light uniforms those of the resident particles; and
        its uniforms' locations."""
        if features not in self._programs:
            program = build_compute_program(
                "splat_shade",
                {"MAX_LIGHTS": MAX_LIGHTS, "FADE_START_RADII": FADE_START_RADII, "FADE_END_RADII": FADE_END_RADII}
                | {name: 1 for name, on in zip(_SHADE_FEATURES, features) if on},
            )
            self._programs[features] = [
                program,
                uniform_locations(program, ("first", "slot_count", "batch_count")),
                None,
            ]
        held = self._programs[features]
        if held[2] is not self._resident.particles:
            _set_light_uniforms(held[0], self._resident.particles)
            held[2] = self._resident.particles
        return held[0], held[1]

    def close(self) -> None:
        """Free the GL objects (the context must be current)."""
        for program, *_ in self._programs.values():
            GL.glDeleteProgram(program)
        GL.glDeleteBuffers(len(self._buffers), list(self._buffers))


def _set_light_uniforms(program: int, particles: ParticleBuffer) -> None:
    GL.glUseProgram(program)
    # Yusov's eye pass: samples per profile row (the rows are in the profiles buffer)
    samples = 0 if particles.profiles is None else particles.profiles.profiles.shape[2]
    GL.glUniform1i(GL.glGetUniformLocation(program, "profile_samples"), samples)
    lights = len(particles.light_directions)
    GL.glUniform1i(GL.glGetUniformLocation(program, "light_count"), lights)
    if lights:
        GL.glUniform3fv(
            GL.glGetUniformLocation(program, "light_direction"),
            lights,
            np.ascontiguousarray(particles.light_directions, dtype=np.float32),
        )
        GL.glUniform3fv(
            GL.glGetUniformLocation(program, "light_radiance"),
            lights,
            np.ascontiguousarray(particles.light_radiance, dtype=np.float32),
        )
    GL.glUniform1i(GL.glGetUniformLocation(program, "phase_kind"), PHASE_NAMES.index(particles.phase))
    GL.glUniform1f(GL.glGetUniformLocation(program, "g"), float(particles.g))

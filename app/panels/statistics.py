"""The Statistics panel: the frame shown, what its plan chose, overdraw, and the frame-time plot."""

from __future__ import annotations

import numpy as np
from imgui_bundle import imgui, implot

from app.editor import Editor
from app.viewport import Viewport


class StatisticsPanel:
    def __init__(self, editor: Editor, viewport: Viewport):
        self.editor, self.viewport = editor, viewport

    def draw(self) -> None:
        editor, shown = self.editor, self.editor.last_stats
        if shown is None:
            return
        frame, plan, kinds = shown.frame, shown.frame.plan, shown.frame.plan.clouds_by_kind
        ms = shown.viewport_ms
        imgui.text(
            f"{ms:6.1f} ms ({1000.0 / max(ms, 1e-3):5.1f} fps)  clouds {frame.cloud_ms:.1f}  "
            f"impostor updates {frame.impostor_update_ms:.1f}  world {frame.world_ms:.1f}  plan {frame.plan_ms:.1f}"
        )
        imgui.text(
            f"GPU: clouds {frame.cloud_gpu_ms:.1f}  impostor updates {frame.impostor_update_gpu_ms:.1f}  "
            f"world {frame.world_gpu_ms:.1f};  CPU {frame.cpu_ms:.1f} (planning and issuing the passes)"
        )
        if frame.drawn_again:
            imgui.text("drawn twice: a draw had more tile pairs than the GPU had room for (both drawings' time above)")
        if shown.picture_reused:
            imgui.text("picture kept: nothing changed since it was drawn (clouds, updates, world: that frame's)")
        if shown.relighting:
            imgui.text(
                f"relighting in the background; shown meanwhile: {shown.shown_illumination} light"
                f" at {shown.shown_time_of_day:.2f} h"
            )
        imgui.text(
            f"particles drawn {frame.particles_drawn}, rendered to impostors {frame.particles_to_impostors}, "
            f"as point sprites {frame.particles_as_points}, as volumes {frame.particles_as_volumes}; "
            f"sorted on the {frame.splat_order.upper()}"
        )
        imgui.text(
            f"impostors drawn {plan.impostors_drawn}, regenerated {shown.impostors_regenerated} "
            f"(total {self.viewport.regenerations_total}), postponed {plan.regenerations_postponed}, "
            f"ring segments built {plan.ring_segments_built}"
        )
        imgui.text(
            f"clouds: full {kinds['full']}, crossfade {kinds['crossfade']}, impostor {kinds['impostor']}, "
            f"inside {kinds['inside']}, ring {kinds['ring']}, culled {kinds['culled']}"
        )
        measured_ms = frame.impostor_update_ms + frame.cloud_ms
        prediction = (
            f"predicted {plan.predicted_ms:.1f} ms against {measured_ms:.1f} measured"
            if plan.priced
            else f"not priced (full 3D draws every cloud in view): {measured_ms:.1f} ms measured"
        )
        imgui.text(
            f"units {plan.units} ({plan.units_grouped} of interpenetrating clouds); {prediction}; "
            f"largest error drawn {plan.accepted_error_tolerances:.2f} x the tolerance ({plan.tolerance_deg:.3f} deg)"
        )
        if plan.drawn_as:
            way = {"units": "each unit as priced", "full": "every unit in full 3D, one draw"}[plan.drawn_as]
            imgui.text(
                f"auto drew {way}; measured: as priced {_measured(plan.measured_units_ms)}, "
                f"all in full 3D {_measured(plan.measured_full_ms)}"
            )
        imgui.text(
            f"objects in clouds {plan.objects_in_clouds}: layers drawn {plan.layers_drawn}, "
            f"rebuilt {plan.layers_rebuilt}"
        )
        imgui.text(f"texture memory {frame.texture_bytes / 2**20:.1f} MiB")
        _, self.viewport.measure_overdraw = imgui.checkbox("Measure overdraw", self.viewport.measure_overdraw)
        imgui.same_line()
        _, self.viewport.heat_map = imgui.checkbox("Overdraw heat map", self.viewport.heat_map)
        if frame.overdraw is not None:
            overdraw = frame.overdraw
            imgui.text(f"overdraw mean {overdraw.mean:.1f}, max {overdraw.max:.0f}, analytic {overdraw.analytic:.1f}")
        history = list(editor.frame_times)
        if implot.begin_plot("Frame time (ms)", imgui.ImVec2(-1, 180)):
            frames = np.arange(len(history), dtype=np.float64)
            implot.setup_axes("frame", "ms", implot.AxisFlags_.auto_fit, 0)
            # scaled to the frames' 95th percentile: the start's shading (seconds) would flatten the rest
            typical = np.percentile([s.viewport_ms for s in history], 95) if history else 1.0
            implot.setup_axis_limits(implot.ImAxis_.y1, 0.0, 1.25 * max(typical, 1.0), implot.Cond_.always)
            for label, times in (
                ("frame", [s.viewport_ms for s in history]),
                ("cloud pass", [s.frame.cloud_ms for s in history]),
                ("impostor updates", [s.frame.impostor_update_ms for s in history]),
                ("world", [s.frame.world_ms for s in history]),
            ):
                implot.plot_line(label, frames, np.array(times, dtype=np.float64))
            implot.end_plot()


def _measured(ms: float) -> str:
    return f"{ms:.1f} ms" if ms > 0.0 else "not yet"

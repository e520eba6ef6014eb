"""The Statistics panel: the frame shown, what its plan chose, overdraw, and the frame-time plot."""

from __future__ import annotations

import numpy as np
from imgui_bundle import hello_imgui, imgui, implot

from app.editor import Editor
from app.viewport import Viewport

#: the gaps between window frames whose median is the rate shown: steady to read, yet new within a second at 60 fps
WINDOW_RATE_GAPS = 30


class StatisticsPanel:
    def __init__(self, editor: Editor, viewport: Viewport):
        self.editor, self.viewport = editor, viewport

    def draw(self) -> None:
        editor, shown = self.editor, self.editor.last_stats
        if shown is None:
            return
        frame = shown.frame
        # the window's rate is what the artist feels (render, GUI and swap; at rest it idles on purpose), the
        # viewport's time the engine's part of it: a picture kept costs under a millisecond, whatever the rate.
        # Tables of short rows: at the editor's default size the panel is 350 pixels wide, and lines of prose
        # were cut there, most of them in the middle
        window_ms = window_frame_ms(editor.frame_times)
        rate = f"{1000.0 / window_ms:.0f} fps" if window_ms > 0.0 else "starting"
        idling = ", idle" if hello_imgui.get_runner_params().fps_idling.is_idling else ""
        _table(
            "passes",
            ("time", "wall ms", "GPU ms"),
            [
                (f"window ({rate}{idling})", f"{window_ms:.1f}", ""),
                ("viewport", f"{shown.viewport_ms:.1f}", ""),
                ("plan", f"{frame.plan_ms:.1f}", ""),
                ("world", f"{frame.world_ms:.1f}", f"{frame.world_gpu_ms:.1f}"),
                ("impostor updates", f"{frame.impostor_update_ms:.1f}", f"{frame.impostor_update_gpu_ms:.1f}"),
                ("clouds", f"{frame.cloud_ms:.1f}", f"{frame.cloud_gpu_ms:.1f}"),
                ("CPU: plan, issuing", f"{frame.cpu_ms:.1f}", ""),
            ],
        )
        if frame.drawn_again:
            imgui.text_wrapped("Drawn twice: a draw had more tile pairs than the GPU had room for (both in the times).")
        if shown.picture_reused:
            imgui.text_wrapped("Picture kept: nothing changed since it was drawn (the passes' times are that frame's).")
        if shown.relighting:
            imgui.text_wrapped(
                f"Relighting in the background; shown meanwhile: {shown.shown_illumination} light"
                f" at {shown.shown_time_of_day:.2f} h."
            )
        _table("counts", ("", ""), _counts(shown, self.viewport.regenerations_total))
        _, self.viewport.measure_overdraw = imgui.checkbox("Measure overdraw", self.viewport.measure_overdraw)
        imgui.same_line()
        _, self.viewport.heat_map = imgui.checkbox("Overdraw heat map", self.viewport.heat_map)
        if frame.overdraw is not None:
            overdraw = frame.overdraw
            imgui.text_wrapped(
                f"Overdraw: mean {overdraw.mean:.1f}, max {overdraw.max:.0f}, analytic {overdraw.analytic:.1f}."
            )
        history = list(editor.frame_times)
        if implot.begin_plot("Frame time (ms)", imgui.ImVec2(-1, 180)):
            frames = np.arange(len(history), dtype=np.float64)
            lines = {
                # each frame's gap to the frame before it: none for the first
                "window": (frames[1:], window_gaps_ms(history)),
                "viewport": (frames, [s.viewport_ms for s in history]),
                "cloud pass": (frames, [s.frame.cloud_ms for s in history]),
                "impostor updates": (frames, [s.frame.impostor_update_ms for s in history]),
                "world": (frames, [s.frame.world_ms for s in history]),
            }
            implot.setup_axes("frame", "ms", implot.AxisFlags_.auto_fit, 0)
            # scaled to the 95th percentile of the window's and the viewport's times: the start's shading (seconds)
            # would flatten the rest
            typical = max(
                (np.percentile(lines[name][1], 95) for name in ("window", "viewport") if lines[name][1]), default=1.0
            )
            implot.setup_axis_limits(implot.ImAxis_.y1, 0.0, 1.25 * max(typical, 1.0), implot.Cond_.always)
            for label, (x, times) in lines.items():
                implot.plot_line(label, x, np.array(times, dtype=np.float64))
            implot.end_plot()


def window_gaps_ms(frames) -> list[float]:
    """Milliseconds from each window frame's start to the next's (`ShownFrame.frame_start_s`)."""
    return [1e3 * (later.frame_start_s - earlier.frame_start_s) for earlier, later in zip(frames, frames[1:])]


def window_frame_ms(frames, last: int = WINDOW_RATE_GAPS) -> float:
    """The median of the last `last` gaps between the window's frames; 0 before two frames."""
    gaps = window_gaps_ms(list(frames)[-last - 1 :])
    return float(np.median(gaps)) if gaps else 0.0


def _counts(shown, regenerations_total: int) -> list[tuple[str, str]]:
    """(what, how many) of the frame shown: its particles, impostors, clouds by kind and the plan's choices."""
    frame, plan = shown.frame, shown.frame.plan
    kinds = plan.clouds_by_kind
    rows = [
        ("particles drawn", f"{frame.particles_drawn}"),
        ("  sorted on the", frame.splat_order.upper()),
        ("  as point sprites", f"{frame.particles_as_points}"),
        ("  as volumes", f"{frame.particles_as_volumes}"),
        ("particles to impostors", f"{frame.particles_to_impostors}"),
        ("impostors drawn", f"{plan.impostors_drawn}"),
        ("  regenerated", f"{shown.impostors_regenerated} (total {regenerations_total})"),
        ("  postponed", f"{plan.regenerations_postponed}"),
        ("ring segments built", f"{plan.ring_segments_built}"),
        ("clouds full, crossfade", f"{kinds['full']}, {kinds['crossfade']}"),
        ("  impostor, inside", f"{kinds['impostor']}, {kinds['inside']}"),
        ("  ring, culled", f"{kinds['ring']}, {kinds['culled']}"),
        ("units (of groups)", f"{plan.units} ({plan.units_grouped})"),
    ]
    measured_ms = frame.impostor_update_ms + frame.cloud_ms
    if plan.priced:
        rows.append(("predicted, measured", f"{plan.predicted_ms:.1f}, {measured_ms:.1f} ms"))
    else:
        rows.append(("not priced (full 3D)", f"{measured_ms:.1f} ms"))
    rows.append(("largest error drawn", f"{plan.accepted_error_tolerances:.2f} x {plan.tolerance_deg:.3f} deg"))
    if plan.drawn_as:
        rows.append(("auto drew", {"units": "units as priced", "full": "all in full 3D"}[plan.drawn_as]))
        rows.append(("  measured as priced", _measured(plan.measured_units_ms)))
        rows.append(("  measured in full 3D", _measured(plan.measured_full_ms)))
    rows.append(("objects in clouds", f"{plan.objects_in_clouds}"))
    rows.append(("  layers drawn, rebuilt", f"{plan.layers_drawn}, {plan.layers_rebuilt}"))
    rows.append(("texture memory", f"{frame.texture_bytes / 2**20:.1f} MiB"))
    return rows


def _table(name: str, headers: tuple[str, ...], rows) -> None:
    """A table of `rows` of short strings, the first column as wide as its text, the others right of it."""
    if not imgui.begin_table(name, len(headers), imgui.TableFlags_.row_bg | imgui.TableFlags_.borders_inner_v):
        return
    imgui.table_setup_column(headers[0], imgui.TableColumnFlags_.width_fixed)
    for header in headers[1:]:
        imgui.table_setup_column(header, imgui.TableColumnFlags_.width_stretch)
    if any(headers[1:]):
        imgui.table_headers_row()
    for row in rows:
        imgui.table_next_row()
        for column, text in enumerate(row):
            imgui.table_set_column_index(column)
            imgui.text(text)
    imgui.end_table()


def _measured(ms: float) -> str:
    return f"{ms:.1f} ms" if ms > 0.0 else "not yet"

"""Screenshot tests of scenes' named views against golden PNGs: the verdicts, the goldens, the HTML report.

Shared by `cloudview check` and the pytest plugin (`cloudcore.pytest_plugin`);
rendering is theirs (`cloudcore.gl.views`), so nothing here imports OpenGL.
A golden is 8-bit RGB PNG at `<goldens>/<scene>/<view>.png`.  A view passes
when its PSNR against its golden is at least the tolerance's and no channel
of any pixel differs by more than its `max_diff` levels (of 255): the PSNR
bounds the overall change, the maximum a small one (a particle moved) that
the PSNR of a whole frame hardly sees.
"""

from __future__ import annotations

import html
import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from cloudcore.maths.paths import camera_on_path
from cloudcore.measure.imagecompare import Difference, compare, diff_image, load_rgb8
from cloudcore.model.errors import SceneError
from cloudcore.model.particle_files import atomic_write
from cloudcore.model.scene import Camera, Scene, View
from cloudcore.model.settings import RenderSettings

#: the goldens' tolerance unless a view or the command line says otherwise (as our own tests/golden: llvmpipe
#: builds and GPUs may differ by rounding, not by a visible change)
DEFAULT_MIN_PSNR_DB = 40.0
DEFAULT_MAX_DIFF = 12
#: frame size (width, height) of a view unless the check says otherwise
DEFAULT_SIZE = (320, 240)


@dataclass(frozen=True)
class Tolerance:
    min_psnr_db: float = DEFAULT_MIN_PSNR_DB
    max_diff: int = DEFAULT_MAX_DIFF

    def for_view(self, view: View) -> Tolerance:
        """This tolerance with what the view's table sets in its place."""
        return Tolerance(
            self.min_psnr_db if view.tolerance_psnr is None else view.tolerance_psnr,
            self.max_diff if view.max_diff is None else view.max_diff,
        )

    def __str__(self) -> str:
        return f"PSNR >= {self.min_psnr_db:g} dB, max |diff| <= {self.max_diff}"


def view_camera(scene: Scene, view: View) -> Camera:
    """Where the view looks from: its camera path at `t`, or its position and look-at; the scene's for the rest."""
    fov = scene.camera.fov_y_deg if view.fov_y_deg is None else view.fov_y_deg
    if view.camera_path is not None:
        return camera_on_path(scene.camera_path(view.camera_path), view.t, fov)
    return Camera(view.position or scene.camera.position, view.look_at or scene.camera.look_at, fov)


def view_settings(view: View) -> RenderSettings:
    return RenderSettings(mode=view.mode, **dict(view.settings))


def find_view(scene: Scene, name: str, source) -> View:
    for view in scene.all_views:
        if view.name == name:
            return view
    known = ", ".join(view.name for view in scene.all_views)
    raise SceneError(source, "views", f"no view named {name!r}; the scene has: {known}")


def golden_path(goldens: Path, scene_name: str, view_name: str) -> Path:
    return Path(goldens) / scene_name / f"{view_name}.png"


#: what a check found; only "pass" passes
PASS, FAIL, MISSING, UNREADABLE, WRONG_SIZE = "pass", "FAIL", "no golden", "unreadable golden", "wrong size"


@dataclass(frozen=True)
class ViewCheck:
    """One view compared with its golden."""

    scene: str
    view: str
    golden: Path
    tolerance: Tolerance
    status: str
    difference: Difference | None = None  # None where there was no golden to compare with
    problem: str = ""  # what is wrong with the golden, for MISSING, UNREADABLE and WRONG_SIZE

    @property
    def passed(self) -> bool:
        return self.status == PASS

    @property
    def label(self) -> str:
        return f"{self.scene}/{self.view}"

    @property
    def detail(self) -> str:
        """The numbers against the tolerance, or what is wrong with the golden."""
        return self.problem if self.difference is None else f"{self.difference} ({self.tolerance})"

    def line(self, update_hint: str = "") -> str:
        """One line for the terminal: the verdict and its detail; where there is no usable golden, how to make
        one (`update_hint`, e.g. the command with --update)."""
        hint = f"; to write it: {update_hint}" if update_hint and self.difference is None else ""
        return f"{self.label}: {self.status}: {self.detail}{hint}"


def check_view(scene: str, view: str, actual: np.ndarray, golden: Path, tolerance: Tolerance) -> ViewCheck:
    """Compare `actual` with the golden PNG at `golden` (a missing, unreadable or wrong-sized one fails)."""

    def verdict(status, difference=None, problem=""):
        return ViewCheck(scene, view, golden, tolerance, status, difference, problem)

    if not golden.is_file():
        return verdict(MISSING, problem=f"{golden} does not exist")
    try:
        expected = load_rgb8(golden)
    except SceneError as error:
        return verdict(UNREADABLE, problem=f"{golden}: {error.problem}")
    if expected.shape != actual.shape:
        return verdict(
            WRONG_SIZE,
            problem=f"{golden} is {expected.shape[1]}x{expected.shape[0]}, the view renders "
            f"{actual.shape[1]}x{actual.shape[0]}",
        )
    difference = compare(actual, expected)
    return verdict(PASS if difference.within(tolerance.min_psnr_db, tolerance.max_diff) else FAIL, difference)


def encode_png(image: np.ndarray) -> bytes:
    """The PNG of an 8-bit image; the same pixels give the same bytes (no time or other metadata is stored)."""
    import imageio.v3 as iio

    return iio.imwrite("<bytes>", image, extension=".png")


def write_png(path: Path, image: np.ndarray) -> None:
    """Write a PNG atomically (a killed check leaves the old golden or the new one, never half of one)."""
    data = encode_png(image)
    try:
        atomic_write(Path(path), lambda f: f.write(data))
    except OSError as error:
        raise SceneError(path, "(file)", f"cannot write: {error.strerror or error}") from None


def update_golden(check: ViewCheck, actual: np.ndarray) -> bool:
    """Write `actual` as the golden unless the golden holds exactly its pixels already; whether it was written."""
    if check.difference is not None and check.difference.max_abs == 0:
        return False
    write_png(check.golden, actual)
    return True


# ---------------------------------------------------------------- the report


@dataclass(frozen=True)
class ReportEntry:
    """A checked view in the report, with its images' paths relative to the report's folder."""

    check: ViewCheck
    actual: str
    expected: str | None
    diff: str | None
    note: str = ""  # e.g. "golden updated"


def keep_images(folder: Path, check: ViewCheck, actual: np.ndarray, note: str = "") -> ReportEntry:
    """Write the view's actual image, and its expected and diff images where the golden could be read, under
    `folder/<scene>/`; the report lists what this returns."""
    stem = Path(check.scene) / check.view
    names = {kind: f"{stem}-{kind}.png" for kind in ("actual", "expected", "diff")}
    write_png(folder / names["actual"], actual)
    if check.status in (PASS, FAIL):
        expected = load_rgb8(check.golden)
        write_png(folder / names["expected"], expected)
        write_png(folder / names["diff"], diff_image(actual, expected))
        return ReportEntry(check, names["actual"], names["expected"], names["diff"], note)
    return ReportEntry(check, names["actual"], None, None, note)


def write_report(folder: Path, entries: list[ReportEntry], title: str = "cloudview check") -> Path:
    """`folder/index.html`: one row per view, the expected, actual and diff images side by side, failures first
    and then the lowest PSNR; every column sorts on a click.  Links are relative: the folder can be moved."""
    rows = "\n".join(_report_row(entry) for entry in sorted(entries, key=_worst_first))
    failed = sum(not entry.check.passed for entry in entries)
    summary = f"{len(entries)} views: {len(entries) - failed} passed, {failed} failed"
    page = _PAGE.format(title=html.escape(title), summary=html.escape(summary), rows=rows)
    path = Path(folder) / "index.html"
    try:
        atomic_write(path, lambda f: f.write(page.encode("utf-8")))
    except OSError as error:
        raise SceneError(path, "(file)", f"cannot write: {error.strerror or error}") from None
    return path


def _worst_first(entry: ReportEntry):
    check = entry.check
    psnr = -1.0 if check.difference is None else check.difference.psnr_db
    return (check.passed, psnr, check.label)


def _report_row(entry: ReportEntry) -> str:
    check, difference = entry.check, entry.check.difference

    def cell(text, sort_key) -> str:
        # the sort key as JSON: numbers sort as numbers (inf and a missing golden as the extremes)
        return f"<td data-sort='{html.escape(json.dumps(sort_key))}'>{html.escape(str(text))}</td>"

    def image(relative) -> str:
        if relative is None:
            return "<td class='none'>none</td>"
        link = html.escape(relative)
        return f"<td><a href='{link}'><img src='{link}' alt='{link}'></a></td>"

    if difference is None:
        numbers = cell("", -1) + cell("", 1e9) + cell("", 1e9)
    else:
        psnr = difference.psnr_db
        numbers = (
            cell("identical" if psnr == float("inf") else f"{psnr:.2f}", min(psnr, 1e9))
            + cell(f"{difference.mean_abs:.3f}", difference.mean_abs)
            + cell(difference.max_abs, difference.max_abs)
        )
    verdict = check.status + (f" ({entry.note})" if entry.note else "")
    detail = check.problem or str(check.tolerance)
    status = "pass" if check.passed else "fail"
    return (
        f"<tr class='{status}'>{cell(check.label, check.label)}"
        f"<td data-sort='{int(check.passed)}'><b>{html.escape(verdict)}</b><br><small>{html.escape(detail)}</small>"
        f"</td>{numbers}{image(entry.expected)}{image(entry.actual)}{image(entry.diff)}</tr>"
    )


_PAGE = """<!DOCTYPE html>
<html lang="en">
<head>
<meta charset="utf-8">
<title>{title}</title>
<style>
body {{ font-family: sans-serif; margin: 1.5em; color: #222; }}
table {{ border-collapse: collapse; }}
th, td {{ border: 1px solid #ccc; padding: 4px 6px; text-align: left; vertical-align: middle; }}
th {{ background: #eee; cursor: pointer; user-select: none; white-space: nowrap; }}
th:hover {{ background: #ddd; }}
th.sorted::after {{ content: " \\25B2"; }}
th.sorted.descending::after {{ content: " \\25BC"; }}
td:nth-child(2) {{ max-width: 15em; overflow-wrap: anywhere; }}
td:nth-child(3), td:nth-child(4), td:nth-child(5) {{ text-align: right; font-variant-numeric: tabular-nums; }}
tr.fail td:nth-child(2) b {{ color: #b00; }}
tr.pass td:nth-child(2) b {{ color: #070; }}
td.none {{ color: #999; text-align: center; width: 160px; }}
/* pixelated: a thumbnail smaller than its image must not blur a few changed pixels of the diff away */
img {{ width: 160px; display: block; background: #000; image-rendering: pixelated; }}
small {{ color: #666; }}
</style>
</head>
<body>
<h1>{title}</h1>
<p>{summary}. Click a column to sort by it, again to reverse; click an image for full size.</p>
<table id="views">
<thead><tr><th>scene / view</th><th>result</th><th>PSNR (dB)</th><th>mean |diff|</th><th>max |diff|</th>
<th>expected</th><th>actual</th><th>diff (x8)</th></tr></thead>
<tbody>
{rows}
</tbody>
</table>
<script>
// sort the rows by a column's data-sort keys (JSON: numbers as numbers); a second click reverses
const table = document.getElementById("views");
table.querySelectorAll("th").forEach((header, column) => header.addEventListener("click", () => {{
  const descending = header.classList.contains("sorted") && !header.classList.contains("descending");
  table.querySelectorAll("th").forEach(other => other.classList.remove("sorted", "descending"));
  header.classList.add("sorted");
  if (descending) header.classList.add("descending");
  const key = row => {{
    const cell = row.children[column];
    return cell.dataset.sort !== undefined ? JSON.parse(cell.dataset.sort) : cell.textContent;
  }};
  const body = table.tBodies[0];
  const rows = Array.from(body.rows).sort((a, b) => {{
    const x = key(a), y = key(b);
    const order = x < y ? -1 : x > y ? 1 : 0;
    return descending ? -order : order;
  }});
  rows.forEach(row => body.appendChild(row));
}}));
</script>
</body>
</html>
"""

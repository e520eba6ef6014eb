"""pytest plugin: screenshot tests of cloud scenes in a user's own test suite (registered as `cloudview`).

    def test_sunset(cloudview_check):
        cloudview_check("scenes/harbour.toml", "sunset", size=(320, 240))

renders the view `sunset` of the scene (a path relative to the test module)
and compares it with `cloudview_goldens/<scene>/<view>.png` beside the test
module, with the view's tolerance, else the one given, else 40 dB and 12
levels (`cloudcore.measure.screenshot_check`).  A failure says why in one line and
keeps the expected, actual and diff images.  Options:

- `--cloudview-update-goldens`: write the goldens whose pixels changed
  instead of comparing (those tests are skipped, saying so);
- `--cloudview-report DIR`: keep every checked view's images under DIR and
  write DIR/index.html at the end of the session.  Without it, a failure's
  images go to pytest's temporary folder (the message names it).

Rendering is headless (EGL; PYOPENGL_PLATFORM is set to egl unless already
set), one context per frame size for the whole session.  Under pytest-xdist
(`pytest -n auto`) each worker process makes its own context; the workers
hand their views to the controller, which writes the one report.
"""

from __future__ import annotations

import os
import pickle
from pathlib import Path

import pytest

GOLDENS_FOLDER = "cloudview_goldens"
#: the key of a pytest-xdist worker's output that carries its report entries to the controller (pickled: they are
#: records of paths and numbers, and xdist's channel carries bytes)
_WORKER_ENTRIES = "cloudview_report_entries"
#: the controller's gathering of its workers' entries
_GATHERED = pytest.StashKey[list]()


def pytest_addoption(parser):
    group = parser.getgroup("cloudview", "cloudview screenshot tests (the cloudview_check fixture)")
    group.addoption(
        "--cloudview-update-goldens",
        action="store_true",
        help=f"write {GOLDENS_FOLDER}/<scene>/<view>.png whose pixels changed instead of comparing",
    )
    group.addoption(
        "--cloudview-report",
        type=Path,
        metavar="DIR",
        help="keep every checked view's expected, actual and diff images in DIR, with DIR/index.html",
    )


class _Session:
    """What the session's screenshot tests share: the renderer (made on first use) and the report's entries."""

    def __init__(self, config, scratch: Path):
        self.config = config
        self.update = config.getoption("--cloudview-update-goldens")
        self.report = config.getoption("--cloudview-report")
        self.scratch = scratch
        self.entries = []
        self._renderer = None

    def renderer(self):
        if self._renderer is None:
            os.environ.setdefault("PYOPENGL_PLATFORM", "egl")  # before OpenGL is first imported
            from cloudcore.gl.views import ViewRenderer

            self._renderer = ViewRenderer()
        return self._renderer

    def close(self) -> None:
        if self._renderer is not None:
            self._renderer.close()
        if self.report is None or not self.entries:
            return
        worker_output = getattr(self.config, "workeroutput", None)
        if worker_output is not None:  # a pytest-xdist worker: the controller writes the report of them all
            worker_output[_WORKER_ENTRIES] = pickle.dumps(self.entries)
        else:
            _write_report(self.report, self.entries)


def _write_report(folder: Path, entries: list) -> None:
    from cloudcore.measure.screenshot_check import write_report

    write_report(folder, entries, "cloudview screenshot tests")


@pytest.hookimpl(optionalhook=True)
def pytest_testnodedown(node, error):
    """pytest-xdist's controller: keep a finished worker's report entries."""
    entries = getattr(node, "workeroutput", {}).get(_WORKER_ENTRIES)
    if entries is not None:
        node.config.stash.setdefault(_GATHERED, []).extend(pickle.loads(entries))


def pytest_sessionfinish(session):
    """pytest-xdist's controller: the one report of every worker's views."""
    gathered = session.config.stash.get(_GATHERED, [])
    folder = session.config.getoption("--cloudview-report")
    if gathered and folder is not None:
        _write_report(folder, gathered)


@pytest.fixture(scope="session")
def _cloudview_session(request, tmp_path_factory):
    session = _Session(request.config, tmp_path_factory.mktemp("cloudview"))
    yield session
    session.close()


@pytest.fixture
def cloudview_check(request, _cloudview_session):
    """`cloudview_check(scene, view="default", *, size=(320, 240), tolerance_psnr=None, max_diff=None)`: render
    the view and fail the test unless it matches its golden; returns the `ViewCheck`."""
    from cloudcore.measure.screenshot_check import (
        DEFAULT_SIZE,
        Tolerance,
        check_view,
        find_view,
        golden_path,
        keep_images,
        update_golden,
    )
    from cloudcore.model.errors import SceneError
    from cloudcore.model.scene import DEFAULT_VIEW_NAME
    from cloudcore.scenes.files import load_scene

    session, here = _cloudview_session, request.path.parent

    def check(scene, view: str = DEFAULT_VIEW_NAME, *, size=DEFAULT_SIZE, tolerance_psnr=None, max_diff=None):
        scene_file = here / scene
        try:
            loaded = load_scene(scene_file)
            chosen = find_view(loaded, view, scene_file)
        except SceneError as error:
            pytest.fail(f"cloudview: {error}", pytrace=False)
        stated = Tolerance().for_view(chosen)
        tolerance = Tolerance(
            stated.min_psnr_db if tolerance_psnr is None else tolerance_psnr,
            stated.max_diff if max_diff is None else max_diff,
        )
        actual = session.renderer().render(loaded, chosen, tuple(size))
        golden = golden_path(here / GOLDENS_FOLDER, scene_file.stem, chosen.name)
        result = check_view(scene_file.stem, chosen.name, actual, golden, tolerance)
        written = session.update and update_golden(result, actual)
        note = ("golden written" if written else "golden unchanged") if session.update else ""
        if session.report is not None:
            session.entries.append(keep_images(session.report, result, actual, note))
        if written:
            pytest.skip(f"{result.label}: golden written to {golden} (was {result.status}: {result.detail})")
        if not result.passed:  # under --cloudview-update-goldens a golden is written or holds these pixels
            folder = session.report if session.report is not None else session.scratch
            if session.report is None:
                keep_images(folder, result, actual)
            pytest.fail(
                f"{result.line('pytest --cloudview-update-goldens')}; images in {folder / result.scene}",
                pytrace=False,
            )
        return result

    return check

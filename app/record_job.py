"""`cloudview record` of a camera path in a subprocess, so that the editor never waits for it.

The scene as edited (saved or not) is written to a private folder with its
mesh files named by absolute path and its particles beside it, then
`python -m cloudcore.cli record` renders it headless: the same engine and the
same frames as the command.  The GUI polls `poll` and shows `progress` (the
command's last output line: its progress bar, then its summary or its error).
"""

from __future__ import annotations

import dataclasses
import shutil
import signal
import subprocess
import sys
import tempfile
import threading
from pathlib import Path

from cloudcore.model.scene import Scene
from cloudcore.scenes.files import save_scene


def standalone(scene: Scene, folder: Path) -> Scene:
    """`scene` as it reads from anywhere: mesh files relative to `folder` made absolute, and particle files
    dropped (a save writes the particles with the copy, never over the originals)."""

    def absolute(name: str | None) -> str | None:
        return None if name is None else str((folder / name).resolve())

    terrain = scene.terrain
    if terrain is not None:
        terrain = dataclasses.replace(terrain, mesh=absolute(terrain.mesh))
    return dataclasses.replace(
        scene,
        terrain=terrain,
        objects=tuple(dataclasses.replace(o, mesh=absolute(o.mesh)) for o in scene.objects),
        clouds=tuple(dataclasses.replace(c, particles_file=None) for c in scene.clouds),
    )


class RecordJob:
    def __init__(
        self, scene: Scene, scene_folder: Path, path_name: str, out: Path, width: int, height: int, fps: float
    ):
        self.out = Path(out)
        self._folder = Path(tempfile.mkdtemp(prefix="cloudview-record-"))
        scene_file = self._folder / "scene.toml"
        save_scene(standalone(scene, scene_folder), scene_file)
        command = [
            sys.executable,
            "-m",
            "cloudcore.cli",
            "record",
            str(scene_file),
            "--camera-path",
            path_name,
            "--out",
            str(self.out),
            "--width",
            str(width),
            "--height",
            str(height),
            "--fps",
            str(fps),
            "--no-overdraw",
        ]
        self._process = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.STDOUT)
        self.progress = "starting"
        self._reader = threading.Thread(target=self._read_output, daemon=True)
        self._reader.start()

    def _read_output(self) -> None:
        """Keep the last non-empty line; tqdm redraws its bar with carriage returns, not newlines."""
        line = b""
        while chunk := self._process.stdout.read1(4096):
            *finished, line = (line + chunk).replace(b"\r", b"\n").split(b"\n")
            for done in reversed(finished):
                if done.strip():
                    self.progress = done.decode("utf-8", "replace").strip()
                    break
        if line.strip():
            self.progress = line.decode("utf-8", "replace").strip()

    def poll(self) -> int | None:
        """The command's exit status once it has finished (its output all read), else None."""
        status = self._process.poll()
        if status is None:
            return None
        self._reader.join()
        shutil.rmtree(self._folder, ignore_errors=True)
        return status

    def stop(self) -> None:
        """Ask it to stop as Ctrl-C does: it finishes the frame it is drawing, so the video plays."""
        if self._process.poll() is None:
            self._process.send_signal(signal.SIGINT)

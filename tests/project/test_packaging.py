"""What a user installing the wheel relies on: the files it ships, its metadata, `cloudview --version`.

The install itself (build the wheel, a fresh venv outside the checkout, render
and shade from another directory) is `.ci/check_wheel`, which CI runs.
"""

import fnmatch
import subprocess
import sys
import tomllib
from importlib import metadata

from tests.conftest import ROOT

PYPROJECT = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))


def test_every_file_the_program_reads_at_run_time_is_declared_package_data():
    declared = PYPROJECT["tool"]["setuptools"]["package-data"]
    for package, folder in (
        ("cloudcore.resources", ROOT / "cloudcore" / "resources"),
        ("cloudcore.gl", ROOT / "cloudcore" / "gl" / "shaders"),
    ):
        base = ROOT.joinpath(*package.split("."))
        files = [f for f in folder.rglob("*") if f.is_file() and f.suffix not in (".py", ".pyc")]
        assert files
        undeclared = [
            str(f.relative_to(base))
            for f in files
            if not any(fnmatch.fnmatch(f.relative_to(base).as_posix(), glob) for glob in declared[package])
        ]
        assert not undeclared, f"not shipped in the wheel: {undeclared}"


def test_the_classifiers_name_the_pythons_verified_and_requires_python_admits_them():
    classifiers = PYPROJECT["project"]["classifiers"]
    versions = sorted(c.rsplit(" ", 1)[1] for c in classifiers if c.startswith("Programming Language :: Python :: 3."))
    assert versions == ["3.11", "3.12", "3.13"]
    assert PYPROJECT["project"]["requires-python"] == ">=3.11"


def test_version_is_one_line_with_ours_python_and_the_gl_libraries():
    result = subprocess.run(
        [sys.executable, "-m", "cloudcore.cli", "--version"],
        capture_output=True,
        text=True,
        env={"COLUMNS": "30", "PATH": ""},
    )
    assert result.returncode == 0, result.stderr
    line = result.stdout.strip()
    assert "\n" not in line
    assert line.startswith(f"cloudview {metadata.version('cloudview')} (Python {sys.version.split()[0]};")
    assert f"PyOpenGL {metadata.version('PyOpenGL')}" in line
    assert f"pyrender-maintained {metadata.version('pyrender-maintained')}" in line

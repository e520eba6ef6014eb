"""`cloudview compare`: exit 0 within tolerance, 1 outside, 2 on bad input in one stderr line."""

import subprocess
import sys

import imageio.v3 as iio
import numpy as np
import pytest

from cloudcore.cli import main

HEIGHT, WIDTH = 48, 64
DEFECT = (slice(20, 30), slice(30, 40))  # rows 20..29, columns 30..39: a 10x10 square


@pytest.fixture
def gradient():
    """A smooth RGB gradient, so any planted defect stands out from its neighbours."""
    y, x = np.mgrid[0:HEIGHT, 0:WIDTH]
    return np.stack([x * 255 // (WIDTH - 1), y * 255 // (HEIGHT - 1), (x + y) % 256], axis=-1).astype(np.uint8)


def write(path, image):
    iio.imwrite(path, image)
    return str(path)


def test_identical_images_exit_0_and_say_identical(tmp_path, gradient, capsys):
    a, b = write(tmp_path / "a.png", gradient), write(tmp_path / "b.png", gradient)
    assert main(["compare", a, b, "--diff", str(tmp_path / "d.png")]) == 0
    assert "identical" in capsys.readouterr().out
    assert not iio.imread(tmp_path / "d.png").any()


def test_a_planted_defect_fails_and_the_diff_image_shows_exactly_it(tmp_path, gradient, capsys):
    defective = gradient.copy()
    defective[DEFECT] += 128  # wraps around: every channel of every defect pixel differs by 128
    a, b = write(tmp_path / "a.png", gradient), write(tmp_path / "b.png", defective)
    diff = tmp_path / "out" / "diff.png"
    assert main(["compare", a, b, "--diff", str(diff)]) == 1
    out = capsys.readouterr().out
    assert "PSNR" in out and "max |diff| 128" in out and "outside the 40 dB tolerance" in out
    rows, cols = np.nonzero(iio.imread(diff).any(axis=-1))
    assert (rows.min(), rows.max(), cols.min(), cols.max()) == (20, 29, 30, 39)
    assert len(rows) == 100  # the whole square, and nothing else


def test_a_lower_tolerance_accepts_the_defect(tmp_path, gradient, capsys):
    defective = gradient.copy()
    defective[DEFECT] += 128
    a, b = write(tmp_path / "a.png", gradient), write(tmp_path / "b.png", defective)
    assert main(["compare", a, b, "--tolerance-psnr", "20"]) == 0
    assert "within the 20 dB tolerance" in capsys.readouterr().out


def test_grey_rgba_and_16_bit_are_read_as_the_same_rgb(tmp_path, gradient, capsys):
    grey = gradient[..., 0]
    rgb = write(tmp_path / "rgb.png", np.repeat(grey[..., None], 3, axis=-1))
    rgba = write(tmp_path / "rgba.png", np.dstack([gradient, np.full_like(grey, 77)]))
    variants = [
        (write(tmp_path / "grey.png", grey), rgb),
        (write(tmp_path / "grey16.png", grey.astype(np.uint16) << 8 | 0xAB), rgb),  # >> 8 drops the low byte
        (rgba, write(tmp_path / "g.png", gradient)),  # alpha is ignored
    ]
    for a, b in variants:
        assert main(["compare", a, b]) == 0, (a, b)
        assert "identical" in capsys.readouterr().out


@pytest.mark.parametrize(
    "case, message",
    [
        ("missing", "missing.png: (file): no such file"),
        ("not an image", "notes.png: (file): not a readable image"),
        ("sizes differ", "small.png: (size): is 32x24, but"),
    ],
)
def test_bad_input_exits_2_in_one_line(tmp_path, gradient, capsys, case, message):
    a = write(tmp_path / "a.png", gradient)
    if case == "missing":
        b = str(tmp_path / "missing.png")
    elif case == "not an image":
        b = str(tmp_path / "notes.png")
        (tmp_path / "notes.png").write_text("not a PNG at all\n")
    else:
        b = write(tmp_path / "small.png", gradient[:24, :32])
    assert main(["compare", a, b, "--diff", str(tmp_path / "d.png")]) == 2
    captured = capsys.readouterr()
    lines = captured.err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("cloudview: error: ") and message in lines[0], captured.err
    assert captured.out == "" and not (tmp_path / "d.png").exists()


def test_compare_imports_neither_opengl_nor_the_gui(tmp_path, gradient):
    a = write(tmp_path / "a.png", gradient)
    code = (
        f"import sys; from cloudcore.cli import main; assert main(['compare', {a!r}, {a!r}]) == 0; "
        "assert not [m for m in sys.modules if m.startswith(('OpenGL', 'imgui_bundle', 'app', 'cloudcore.gl'))]"
    )
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert result.returncode == 0, result.stderr

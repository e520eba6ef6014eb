"""Fuzzing the scene loader: malformed input is a one-line SceneError naming the file, never a crash.

Four families of bad input, each against a real saved scene (the `small_scene`
fixture, which touches every field and keeps one cloud in a .npy):

1. the TOML text mutated byte by byte (inserts, deletes, replacements, truncation,
   invalid UTF-8) or line by line (odd `key = value` lines and table headers), and
   pure random text or bytes;
2. valid TOML of the wrong shape: values replaced by wrong types, NaN, Inf, huge or
   negative numbers, arrays of the wrong length, nested tables; keys deleted or added;
3. the cloud's .npy truncated, its bytes corrupted, its header forged, replaced by
   an array of the wrong shape or dtype (object arrays too: nothing is unpickled),
   or deleted;
4. for every refusal: one line, naming the file.

The fixtures are read-only inside each test, so reusing a function-scoped one
across hypothesis examples is safe (hence the suppressed health check).
"""

import copy
import io
import math
import os
import pickle
import subprocess
import sys
import tomllib

import numpy as np
import pytest
import tomlkit
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

from cloudcore.model.errors import SceneError
from cloudcore.model.scene import Scene
from cloudcore.scenes.files import load_scene, save_scene
from cloudcore.scenes.limits import MAX_MAGNITUDE
from tests.conftest import ROOT

# CLOUDVIEW_FUZZ_EXAMPLES=5000 fuzzes deeper; the default keeps this file to a few seconds.
FUZZ = settings(
    max_examples=int(os.environ.get("CLOUDVIEW_FUZZ_EXAMPLES", 150)),
    deadline=None,
    suppress_health_check=[HealthCheck.function_scoped_fixture],
)
NPY_FIELD = "clouds[1].particles_file"  # small_scene's second cloud has 200 particles: saved to a .npy


@pytest.fixture
def saved(tmp_path, small_scene):
    """small_scene saved as s.toml (one cloud inline, one in s.particles/large.npy)."""
    path = tmp_path / "s.toml"
    save_scene(small_scene, path)
    npy = tmp_path / "s.particles" / "large.npy"
    assert npy.is_file()
    return path


def load_or_refuse(path):
    """load_scene's Scene, or its SceneError checked for the one-line contract; any other exception fails."""
    try:
        scene = load_scene(path)
    except SceneError as error:
        check_refusal(error, path)
        return error
    assert isinstance(scene, Scene)
    check_invariants(scene)
    return scene


def check_refusal(error: SceneError, path):
    message = str(error)
    assert len(message.splitlines()) == 1 and "\n" not in message and "\r" not in message, repr(message)
    assert error.source == str(path)
    assert path.name in message
    assert message.startswith(f"{path}: {error.field}: "), repr(message)
    assert error.problem, repr(message)


def check_invariants(scene: Scene):
    """What a loaded scene promises, whatever the file said."""
    c = scene.camera
    assert np.all(np.isfinite(c.position + c.look_at)) and c.position != c.look_at
    assert 1 <= c.fov_y_deg <= 170
    for light in scene.lighting.lights:
        assert np.all(np.isfinite(light.direction)) and abs(np.linalg.norm(light.direction) - 1) < 1e-9, light
        assert min(light.color) >= 0 and light.intensity >= 0
    s = scene.shading
    assert 0 <= s.albedo <= 1 and 0 <= s.optical_depth < math.inf and abs(s.g) < 1
    for cloud in scene.clouds:
        p = cloud.particles
        assert p.dtype == np.float64 and p.ndim == 2 and p.shape[1] == 4
        assert np.all(np.isfinite(p)) and np.all(p[:, 3] > 0)
        if cloud.sprite is not None:
            assert cloud.sprite.rows and all(0 <= r < 4 for r in cloud.sprite.rows)
            low, high = cloud.sprite.rotation_deg
            assert low <= high <= low + 360 and 0 <= cloud.sprite.flat_bottom_fraction <= 1
        if cloud.artist is not None:
            levels = np.array(cloud.artist.levels)
            assert levels.shape == (5, 5) and np.all(np.diff(levels[:, 0]) > 0) and np.all(levels >= 0)
            assert np.all(levels <= 1) and 0 <= min(cloud.artist.directional_range)
        assert cloud.shading_group_size is None or 0 < cloud.shading_group_size < math.inf
    for item in scene.objects + scene.camera_paths:
        assert isinstance(item.name, str)


# ---------------------------------------------------------------- 1. malformed TOML text

TOKENS = [
    '"',
    "'",
    "[",
    "]",
    "[[",
    "]]",
    "{",
    "}",
    "=",
    ",",
    ".",
    "#",
    "\n",
    "\r",
    " ",
    "\t",
    "\\",
    '"""',
    "'''",
    "-",
    "+",
    "_",
    "e",
    "0",
    "9",
    "nan",
    "inf",
    "-inf",
    "1e999",
    "9" * 40,
    "9" * 5000,
    "0x7f",
    "0o8",
    "true",
    "1979-05-27T07:32:00Z",
    "\n[camera]\n",
    "\n[[clouds]]\n",
    "\n[clouds]\n",
    "particles",
    "\x00",
    "\ufeff",
    "\u2028",
    "é",
    "\U0001f600",
    "[" * 2000,
]
BYTE_TOKENS = [t.encode("utf-8") for t in TOKENS] + [b"\xff", b"\xc3", b"\xe2\x80", b"\xed\xa0\x80", b"\x80"]
char_edits = st.tuples(
    st.sampled_from(["insert", "delete", "replace"]),
    st.integers(0, 10**6),
    st.integers(1, 12),
    st.sampled_from(BYTE_TOKENS) | st.binary(min_size=1, max_size=4),
)

# Line edits speak a little TOML, so that mutants get past the parser: a `key = value` line with
# a key of the format (or an odd one) and an odd value, a table header, or a line deleted or repeated.
LINE_KEYS = [
    "name",
    "particles",
    "particles_file",
    "position",
    "look_at",
    "fov_y_deg",
    "direction",
    "color",
    "intensity",
    "time_of_day",
    "ambient",
    "albedo",
    "optical_depth",
    "phase",
    "g",
    "kind",
    "size",
    "resolution",
    "height",
    "seed",
    "mesh",
    "primitive",
    "scale",
    "path",
    "keys",
    "description",
    "rows",
    "rotation_deg",
    "facing",
    "flat_bottom_fraction",
    "levels",
    "level_percent_by_hour",
    "directional_colour_by_hour",
    "directional_range",
    "shading_group_size",
    r'"a\nb"',
    '""',
    '"x.y"',
    "x.y",
    r'"\u001b[31m"',
]
LINE_VALUES = [
    "1",
    "-1",
    "0",
    "-0.0",
    "nan",
    "-inf",
    "1e308",
    "1e-320",
    "9" * 30,
    "1" + "0" * 400,
    "9" * 5000,
    "true",
    '"x"',
    '"1.0"',
    '""',
    r'"a\nb"',
    '"s.particles/large.npy"',
    '"."',
    "[]",
    "[[]]",
    "[1, 2]",
    "[1, 2, 3]",
    '["1", "2", "3"]',
    "[true, false, true]",
    "[1e300, 1e300, 0]",
    "[0, 1e-320, 0]",
    "[1, nan, 3]",
    "[" + "9" * 400 + ", 0, 0]",
    "[[1, 2, 3, 4]]",
    '[["1", 2, 3, 4]]',
    "[[1, 2, 3, -4]]",
    "[[1, 2, 3]]",
    "[[0, 0, 0, 0, 0, 0, 0], [0, 0, 0, 0, 0, 0, 0]]",
    "{}",
    "{ x = 1 }",
    "[{}]",
    "[" * 3000 + "]" * 3000,
    "1979-05-27",
    "07:32:00",
]
LINE_TABLES = [
    "[camera]",
    "[lighting]",
    "[shading]",
    "[terrain]",
    "[[clouds]]",
    "[[objects]]",
    "[[camera_paths]]",
    "[[lighting.lights]]",
    "[lighting.lights]",
    "[[camera]]",
    "[clouds.x]",
    "[x]",
    "[clouds.sprite]",
    "[clouds.artist]",
    "[[clouds.artist]]",
]
line_edits = st.tuples(
    st.just("line"),
    st.integers(0, 10**6),
    st.sampled_from(["value", "value", "set", "table", "delete", "repeat"]),
    st.tuples(st.sampled_from(LINE_KEYS), st.sampled_from(LINE_VALUES)),
    st.sampled_from(LINE_TABLES),
)


def mutate(data: bytes, edit_list, cut) -> bytes:
    for kind, position, *how in edit_list:
        if kind == "line":
            lines = data.split(b"\n")
            operation, (key, value), table = how
            if operation == "value":  # a new value for a one-line `key = value`
                candidates = [i for i, line in enumerate(lines) if b" = " in line and not line.endswith(b"[")]
                at = candidates[position % len(candidates)] if candidates else 0
            elif operation in ("set", "table"):  # not inside a multi-line array: after a table header, or at an end
                starts = [0, len(lines)] + [i + 1 for i, line in enumerate(lines) if line.startswith(b"[")]
                at = starts[position % len(starts)]
            else:
                at = position % (len(lines) + 1)
            if operation == "value" and at < len(lines):
                lines[at] = lines[at].partition(b" = ")[0] + b" = " + value.encode("utf-8")
            elif operation == "set":
                lines.insert(at, f"{key} = {value}".encode())
            elif operation == "table":
                lines.insert(at, table.encode("utf-8"))
            elif at < len(lines):
                lines[at : at + 1] = [] if operation == "delete" else [lines[at]] * 2
            data = b"\n".join(lines)
            continue
        length, token = how
        at = position % (len(data) + 1)
        if kind == "insert":
            data = data[:at] + token + data[at:]
        elif kind == "delete":
            data = data[:at] + data[at + length :]
        else:
            data = data[:at] + token + data[at + length :]
    if cut is not None:
        data = data[: cut % (len(data) + 1)]
    return data


@FUZZ
@given(edit_list=st.lists(char_edits, min_size=1, max_size=5), cut=st.none() | st.integers(0, 10**6))
def test_mutated_scene_text_loads_or_is_refused_in_one_line(saved, edit_list, cut):
    mutant = saved.with_name("mutant.toml")  # beside s.toml, so particles_file still resolves
    mutant.write_bytes(mutate(saved.read_bytes(), edit_list, cut))
    load_or_refuse(mutant)


@FUZZ
@given(edit_list=st.lists(line_edits, min_size=1, max_size=3) | st.lists(line_edits | char_edits, max_size=4))
def test_mutated_scene_lines_load_or_are_refused_in_one_line(saved, edit_list):
    mutant = saved.with_name("lines.toml")
    mutant.write_bytes(mutate(saved.read_bytes(), edit_list, None))
    load_or_refuse(mutant)


@FUZZ
@given(cut=st.integers(0, 10**6))
def test_truncated_scene_text_loads_or_is_refused_in_one_line(saved, cut):
    mutant = saved.with_name("cut.toml")
    mutant.write_bytes(mutate(saved.read_bytes(), [], cut))
    load_or_refuse(mutant)


TOML_ALPHABET = list('[]{}=".,#\n \t0123456789abcdefinrtux+-_:TZ') + ["camera", "clouds", "name", "particles"]


@FUZZ
@given(
    content=st.one_of(
        st.binary(max_size=400),
        st.text(max_size=300).map(lambda s: s.encode("utf-8")),
        st.lists(st.sampled_from(TOML_ALPHABET), max_size=120).map(lambda t: "".join(t).encode("utf-8")),
    )
)
def test_random_bytes_load_or_are_refused_in_one_line(tmp_path, content):
    path = tmp_path / "random.toml"
    path.write_bytes(content)
    load_or_refuse(path)


def test_a_folder_or_a_missing_file_is_refused(tmp_path):
    for path in (tmp_path, tmp_path / "missing.toml"):
        assert isinstance(load_or_refuse(path), SceneError)


# ---------------------------------------------------------------- 2. valid TOML, wrong structure

WEIRD_NUMBERS = [
    math.nan,
    -math.nan,
    math.inf,
    -math.inf,
    -1,
    0,
    -0.0,
    1e308,
    -1e308,
    5e-324,
    1e-320,
    1e200,
    -1e200,
    2**63 - 1,
    -(2**63),
    10**30,
    10**400,
    -(10**400),
    2**1024,
]
scalars = st.one_of(
    st.sampled_from(WEIRD_NUMBERS),
    st.booleans(),
    st.integers(),
    st.floats(),
    st.text(max_size=8),
    st.sampled_from(
        [
            "",
            "nan",
            "1.0",
            "rayleigh",
            "box",
            "mesh",
            "s.particles/large.npy",
            "../nowhere.npy",
            ".",
            "a\nb",
            "\x1b[31m",
            "/",
            "s.toml",
        ]
    ),
    st.datetimes(),
    st.dates(),
    st.times(),
)
odd_scalars = st.sampled_from(WEIRD_NUMBERS + [True, False, "1.0", "nan", "", "a\nb"])
wrong_values = st.one_of(
    odd_scalars,
    st.lists(odd_scalars | st.floats(), min_size=3, max_size=3),  # a 3-vector with odd components
    st.recursive(
        scalars,
        lambda inner: st.lists(inner, max_size=5) | st.dictionaries(st.text(max_size=6), inner, max_size=3),
        max_leaves=10,
    ),
    st.lists(st.sampled_from(WEIRD_NUMBERS) | st.floats(), max_size=8),  # vectors of the wrong length or values
    st.lists(st.lists(st.sampled_from(WEIRD_NUMBERS) | st.floats() | st.integers(), max_size=8), max_size=4),  # rows
    st.lists(
        st.dictionaries(st.sampled_from(["name", "particles", "direction", "keys", "x"]), scalars, max_size=3),
        max_size=3,
    ),  # arrays of tables
)
keys = st.sampled_from(
    [
        "name",
        "particles",
        "particles_file",
        "direction",
        "keys",
        "albedo",
        "size",
        "mesh",
        "lights",
        "",
        "a\nb",
        "x.y",
        "\x1b[31m",
    ]
) | st.text(max_size=6)


def all_paths(node, prefix=()):
    yield prefix
    if isinstance(node, dict):
        for key, value in node.items():
            yield from all_paths(value, prefix + (key,))
    elif isinstance(node, list):
        for index, value in enumerate(node):
            yield from all_paths(value, prefix + (index,))


def at(node, path):
    for step in path:
        node = node[step]
    return node


@st.composite
def restructured(draw, base: dict):
    """A deep copy of `base` with 1 to 3 values replaced, deleted or added."""
    doc = copy.deepcopy(base)
    for _ in range(draw(st.integers(1, 3))):
        operation = draw(st.sampled_from(["replace field", "replace field", "replace", "delete", "add"]))
        paths = [p for p in all_paths(doc) if p]  # anything but the document itself
        if operation == "add":  # to a table
            paths = [()] + [p for p in paths if isinstance(at(doc, p), dict)]
        elif operation == "replace field":  # a key's value, not one number of a particle array
            paths = [p for p in paths if isinstance(p[-1], str)]
        path = draw(st.sampled_from(paths))
        if operation == "add":
            at(doc, path)[draw(keys)] = draw(wrong_values)
        elif operation.startswith("replace"):
            at(doc, path[:-1])[path[-1]] = draw(wrong_values)
        else:
            del at(doc, path[:-1])[path[-1]]
    return doc


@FUZZ
@given(data=st.data())
def test_wrong_types_and_values_load_or_are_refused_in_one_line(saved, data):
    base = tomllib.loads(saved.read_text(encoding="utf-8"))
    doc = data.draw(restructured(base))
    mutant = saved.with_name("wrong.toml")
    mutant.write_text(tomlkit.dumps(doc), encoding="utf-8")
    load_or_refuse(mutant)


def test_the_unmutated_documents_load(saved):
    """The fuzzers start from scenes that load, so what they find is due to the mutation."""
    assert isinstance(load_or_refuse(saved), Scene)
    again = saved.with_name("again.toml")
    again.write_text(tomlkit.dumps(tomllib.loads(saved.read_text(encoding="utf-8"))), encoding="utf-8")
    assert load_scene(again) == load_scene(saved)


# Each of these crashed (or slipped through) before the fix; the field they must be refused at.
CRASHERS = [
    ("[camera]\nfov_y_deg = " + "1" * 5000, "(toml)"),  # tomllib's int digit limit: a plain ValueError
    ("description = " + "[" * 5000 + "]" * 5000, "(toml)"),  # RecursionError in tomllib
    ("[camera]\nfov_y_deg = " + "1" * 400, "camera.fov_y_deg"),  # OverflowError in float()
    ("[camera]\nposition = [" + "9" * 400 + ", 0, 0]", "camera.position"),  # OverflowError in numpy
    ('[[clouds]]\nname = "c"\nparticles = [[0, 0, 0, 1' + "0" * 400 + "]]", "clouds[0].particles"),
    ("[terrain]\nsize = [1" + "0" * 400 + ", 10]", "terrain.size.x"),
    ('[camera]\nposition = ["0", "500", "1500"]', "camera.position"),  # strings were read as numbers
    ("[camera]\nlook_at = [true, false, true]", "camera.look_at"),  # and booleans too
    ('[[clouds]]\nname = "c"\nparticles = [["1", 2, 3, 4]]', "clouds[0].particles"),
    ('"a\\nb" = 1', "a\\nb"),  # a newline in a key made a two-line message
    ('[[clouds]]\nname = "c"\nparticles_file = "x\\ny.npy"', "clouds[0].particles_file"),
]


@pytest.mark.parametrize("text, field", CRASHERS)
def test_crashers_found_by_fuzzing_are_refused(tmp_path, text, field):
    path = tmp_path / "crash.toml"
    path.write_text(text, encoding="utf-8")
    error = load_or_refuse(path)
    assert isinstance(error, SceneError)
    assert error.field == field


def test_huge_light_direction_is_normalised_not_zeroed(tmp_path):
    path = tmp_path / "light.toml"
    path.write_text(
        "[[lighting.lights]]\ndirection = [1e300, 1e300, 0]\n[[lighting.lights]]\ndirection = [0, 1e-320, 0]\n"
    )
    lights = load_or_refuse(path).lighting.lights
    np.testing.assert_allclose(lights[0].direction, [0.5**0.5, 0.5**0.5, 0])
    assert lights[1].direction == (0.0, 1.0, 0.0)


# ---------------------------------------------------------------- 3. corrupted .npy particle files


def npy_of(saved):
    return saved.parent / "s.particles" / "large.npy"


def refused_at_npy(outcome, saved):
    assert isinstance(outcome, SceneError), "a broken particle file was accepted"
    assert outcome.field == NPY_FIELD, str(outcome)


def load_with_npy(saved, content: bytes):
    npy = npy_of(saved)
    original = npy.read_bytes()
    npy.write_bytes(content)
    try:
        return load_or_refuse(saved)
    finally:
        npy.write_bytes(original)


@FUZZ
@given(data=st.data())
def test_truncated_npy_is_refused(saved, data):
    original = npy_of(saved).read_bytes()
    length = data.draw(st.integers(0, len(original) - 1))
    outcome = load_with_npy(saved, original[:length])
    refused_at_npy(outcome, saved)
    assert "large.npy" in str(outcome)


# numpy reads the header with ast.literal_eval, which warns about odd escapes and overflows
@pytest.mark.filterwarnings("ignore:invalid escape sequence", "ignore:overflow encountered:RuntimeWarning")
@FUZZ
@given(data=st.data())
def test_corrupted_npy_bytes_load_or_are_refused(saved, data):
    original = bytearray(npy_of(saved).read_bytes())
    header_end = 10 + int.from_bytes(original[8:10], "little")
    in_header = data.draw(st.booleans())
    for _ in range(data.draw(st.integers(1, 4))):
        where = data.draw(st.integers(0, header_end - 1) if in_header else st.integers(0, len(original) - 1))
        original[where] = data.draw(st.integers(0, 255) | st.sampled_from(list(b"()[]{},:'\"0123456789-\n \\")))
    outcome = load_with_npy(saved, bytes(original))
    if isinstance(outcome, SceneError):
        assert outcome.field == NPY_FIELD


def save_npy(array, *, allow_pickle=False) -> bytes:
    buffer = io.BytesIO()
    np.save(buffer, array, allow_pickle=allow_pickle)
    return buffer.getvalue()


non_numeric_dtypes = st.sampled_from(
    [np.bool_, np.complex128, "U3", "S3", "datetime64[s]", "timedelta64[s]", np.dtype([("x", "<f8"), ("r", "<f8")])]
)
numeric_dtypes = st.sampled_from(
    [np.float64, np.float32, np.float16, np.int8, np.int64, np.uint16, np.uint64, np.longdouble, ">f8"]
)
shapes = hnp.array_shapes(min_dims=0, max_dims=4, min_side=0, max_side=6)


@FUZZ
@given(array=hnp.arrays(non_numeric_dtypes, shapes))
def test_npy_of_a_non_numeric_dtype_is_refused(saved, array):
    refused_at_npy(load_with_npy(saved, save_npy(array)), saved)


@FUZZ
@given(
    array=hnp.arrays(
        np.dtype(object),
        hnp.array_shapes(max_dims=3, max_side=4),
        elements=st.integers() | st.text(max_size=3) | st.floats() | st.none(),
    )
)
def test_npy_of_objects_is_refused_without_unpickling(saved, array):
    outcome = load_with_npy(saved, save_npy(array, allow_pickle=True))
    refused_at_npy(outcome, saved)
    assert "large.npy" in str(outcome)


@FUZZ
@given(array=hnp.arrays(numeric_dtypes, shapes.filter(lambda s: not (len(s) == 2 and s[1] == 4))))
def test_npy_of_the_wrong_shape_is_refused(saved, array):
    outcome = load_with_npy(saved, save_npy(array))
    if array.size == 0:  # an empty cloud, whatever its empty shape: accepted as no particles
        assert isinstance(outcome, SceneError) or len(outcome.clouds[1].particles) == 0
    else:
        refused_at_npy(outcome, saved)


@FUZZ
@given(
    array=hnp.arrays(
        numeric_dtypes, st.tuples(st.integers(0, 30), st.just(4)), elements={"allow_nan": True, "allow_infinity": True}
    )
)
def test_npy_of_the_right_shape_is_checked_value_by_value(saved, array):
    with np.errstate(over="ignore", invalid="ignore"):
        as_float = np.asarray(array, dtype=np.float64)
        good = bool(
            np.all(np.isfinite(as_float)) and np.all(as_float[:, 3] > 0) and np.all(np.abs(as_float) <= MAX_MAGNITUDE)
        )
    outcome = load_with_npy(saved, save_npy(array))
    if good:
        np.testing.assert_array_equal(outcome.clouds[1].particles, as_float)
    else:
        refused_at_npy(outcome, saved)


header_dicts = st.fixed_dictionaries(
    {
        "descr": st.sampled_from(
            ["'<f8'", "'<f4'", "'|b1'", "'|O'", "'<U3'", "'xyz'", "3", "None", "[('a', '<f8')]", "'<c16'", "'V0'"]
        ),
        "fortran_order": st.sampled_from(["False", "True", "'yes'", "0"]),
        "shape": st.lists(
            st.integers(-3, 8) | st.sampled_from([2**31, 2**40, 10**13, 2**62, 2**63, 2**70, 10**30]), max_size=3
        ).map(lambda s: "(" + "".join(f"{n}, " for n in s) + ")"),
    },
    optional={"extra": st.sampled_from(["1", "'x'"])},
)


@pytest.mark.filterwarnings(
    "ignore:overflow encountered:RuntimeWarning", "ignore:invalid value encountered:RuntimeWarning"
)
@FUZZ
@given(
    header=header_dicts,
    version=st.sampled_from([1, 2, 3]),
    drop=st.sets(st.sampled_from(["descr", "shape"])),
    payload=st.binary(max_size=200),
    cut=st.none() | st.integers(0, 200),
)
def test_forged_npy_headers_load_or_are_refused(saved, header, version, drop, payload, cut):
    text = "{" + "".join(f"'{k}': {v}, " for k, v in header.items() if k not in drop) + "}"
    body = text.encode("latin1")
    body += b" " * ((64 - (10 + 2 * (version > 1) + len(body) + 1) % 64) % 64) + b"\n"
    size = len(body).to_bytes(2 if version == 1 else 4, "little")
    content = b"\x93NUMPY" + bytes([version, 0]) + size + body
    if cut is not None:
        content = content[:cut]
    outcome = load_with_npy(saved, content + payload)
    if isinstance(outcome, SceneError):
        assert outcome.field == NPY_FIELD


@pytest.mark.parametrize("descr, shape", [("'V0'", "(-1,)"), ("'S0'", "(-2, 4)"), ("'<f8'", "(-1, 4)")])
def test_a_header_of_empty_items_or_a_negative_dimension_is_refused_not_a_crash(saved, descr, shape):
    """'V0' of shape (-1,) killed the process with SIGFPE inside numpy's memmap (the fuzz test above found it):
    the header is checked before the file is mapped, in a child so that a crash fails this test, not the run."""
    text = f"{{'descr': {descr}, 'fortran_order': False, 'shape': {shape}, }}".encode("latin1")
    body = text + b" " * ((64 - (10 + len(text) + 1) % 64) % 64) + b"\n"
    npy_of(saved).write_bytes(b"\x93NUMPY\x01\x00" + len(body).to_bytes(2, "little") + body + b"\x00" * 64)
    child = subprocess.run(
        [sys.executable, "-c", LOAD_AND_SAY, str(saved)], capture_output=True, text=True, timeout=120, cwd=ROOT
    )
    assert child.returncode == 0, f"the load died ({child.returncode}): {child.stderr}"
    field, message = child.stdout.strip().split("\t")
    assert field == NPY_FIELD and "not a readable .npy" in message, message


#: a child's load of a scene: the field and message of its refusal, tab-separated
LOAD_AND_SAY = """
import sys
from cloudcore.model.errors import SceneError
from cloudcore.scenes.files import load_scene
try:
    load_scene(sys.argv[1])
except SceneError as error:
    print(error.field, str(error), sep="\\t")
"""


@pytest.mark.parametrize(
    "content",
    [
        b"",
        b"\x93NUMPY",
        b"\x93NUMPY\x01\x00\xff\xff",
        pickle.dumps([[1.0, 2.0, 3.0, 4.0]]),
        b"PK\x03\x04",
        b"\x93NUMPY\x01\x00\x10\x00{'descr': ",
        b"\x93NUMPY\x01\x00"
        + (10016).to_bytes(2, "little")
        + b"{'descr': '<f8', 'fortran_order': False, 'shape': (1, 4), 'pad': '"
        + b"x" * 9950
        + b"'}"
        + b" " * 8
        + b"\n",
    ],
)
def test_garbage_npy_is_refused(saved, content):
    outcome = load_with_npy(saved, content)
    refused_at_npy(outcome, saved)
    assert "large.npy" in str(outcome)


def test_npz_instead_of_npy_is_refused(saved):
    buffer = io.BytesIO()
    np.savez(buffer, particles=np.ones((3, 4)))
    refused_at_npy(load_with_npy(saved, buffer.getvalue()), saved)


class _Trap:
    """Unpickling this creates a file: proof that the loader ran pickle."""

    def __init__(self, path):
        self.path = path

    def __reduce__(self):
        return (open, (self.path, "w"))


def test_pickled_payload_is_never_run(saved):
    trap = saved.parent / "unpickled"
    array = np.empty((2, 4), dtype=object)
    array[:] = _Trap(str(trap))
    outcome = load_with_npy(saved, save_npy(array, allow_pickle=True))
    refused_at_npy(outcome, saved)
    assert not trap.exists()
    # and the raw pickle stream (no .npy header) is refused the same way
    refused_at_npy(load_with_npy(saved, pickle.dumps(_Trap(str(trap)))), saved)
    assert not trap.exists()


def test_missing_npy_or_folder_is_refused_naming_the_file(saved):
    npy = npy_of(saved)
    npy.unlink()
    outcome = load_or_refuse(saved)
    refused_at_npy(outcome, saved)
    assert "large.npy" in str(outcome) and "no such file" in str(outcome)
    npy.parent.rmdir()
    refused_at_npy(load_or_refuse(saved), saved)
    npy.mkdir(parents=True)  # a folder where the file should be
    refused_at_npy(load_or_refuse(saved), saved)

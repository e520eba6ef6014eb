"""The layers of docs/architecture.md, read from the imports.

OpenGL only in cloudcore/gl; a scene model that depends on no feature; every module of the engine imports only
its own layer and those below it (`LAYERS`), and no two parts of the engine import each other, however roundabout.
"""

import ast
from pathlib import Path

import pytest

from tests.conftest import ROOT

ENGINE = ROOT / "cloudcore"
GL_LIBRARIES = ("OpenGL", "pyrender", "imgui_bundle", "glfw")
#: the scene model: records only, so every feature may read them and none is needed to make one
MODEL_MODULES = ("model/scene.py", "model/cloud_records.py", "model/settings.py")
MODEL_MAY_IMPORT = ("cloudcore.model.cloud_records", "cloudcore.model.errors")
#: the engine's parts (a package of cloudcore, or one of its top-level modules), lowest layer first: a module
#: imports from its own layer and the layers below, never from one above
LAYERS = (
    # the scene model: its records, the settings, the one error, the low-level readers of its files
    ("model",),
    # what knows no feature: small maths, the process, shipped data
    ("maths", "runtime", "resources"),
    # the world around the clouds (the camera, the sun, the terrain, objects, the wind) and the air
    ("world", "atmosphere"),
    # the particles and how they look besides the light: Wang's artist tools, Yusov's cloud fields and their weather
    ("artist", "field"),
    # what is done with the particles: the light, the level of detail
    ("light", "lod"),
    # the frame's particles: their buffer (lit, carried, weighed), a draw's batch far to near, point sprites
    ("particles",),
    # what a frame drew and cost
    ("stats",),
    # offline measurement: benchmarks, recordings, screenshot checks, the path-traced truth and comparisons with it
    ("measure",),
    # scenes coming in and changed: the files, what the renderer can draw, the artist's edits, clouds from and to
    # other tools' files
    ("scenes",),
    # OpenGL
    ("gl",),
    # the command and the pytest plugin
    ("cli", "pytest_plugin"),
)
LAYER_OF = {part: level for level, parts in enumerate(LAYERS) for part in parts}


def imported_modules(path: Path) -> set[str]:
    """Every module `path` imports, absolute, at any depth of its code (function-level imports too)."""
    names = set()
    for node in ast.walk(ast.parse(path.read_text(), filename=str(path))):
        if isinstance(node, ast.Import):
            names.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            names.add(node.module)
    return names


def part_of(module: str) -> str | None:
    """The engine's part a module named `module` belongs to (`cloudcore.lod.plan.planner`: "lod"); None outside
    the engine and for the package `cloudcore` itself."""
    names = module.split(".")
    return names[1] if names[0] == "cloudcore" and len(names) > 1 else None


def _engine_modules():
    return sorted(ENGINE.rglob("*.py"))


def _engine_modules_outside_gl():
    return [p for p in _engine_modules() if (ENGINE / "gl") not in p.parents]


def _module_name(path: Path) -> str:
    """`cloudcore/lod/plan/planner.py`: "cloudcore.lod.plan.planner"; a package's `__init__.py` is the package."""
    names = path.relative_to(ROOT).with_suffix("").parts
    return ".".join(names[:-1] if names[-1] == "__init__" else names)


def _part_imports() -> dict[str, set[str]]:
    """Per part of the engine, the other parts it imports."""
    imports: dict[str, set[str]] = {}
    for path in _engine_modules():
        part = part_of(_module_name(path))
        if part is None:
            continue
        others = {part_of(m) for m in imported_modules(path)} - {None, part}
        imports.setdefault(part, set()).update(others)
    return imports


def import_loops(imports: dict[str, set[str]]) -> list[list[str]]:
    """The loops of an import graph: its strongly connected components of more than one node (Tarjan)."""
    index, low, on_stack, stack, loops = {}, {}, set(), [], []

    def visit(node):
        index[node] = low[node] = len(index)
        stack.append(node)
        on_stack.add(node)
        for other in sorted(imports.get(node, ())):
            if other not in index:
                visit(other)
                low[node] = min(low[node], low[other])
            elif other in on_stack:
                low[node] = min(low[node], index[other])
        if low[node] == index[node]:
            component = []
            while True:
                member = stack.pop()
                on_stack.discard(member)
                component.append(member)
                if member == node:
                    break
            if len(component) > 1:
                loops.append(sorted(component))

    for node in sorted(imports):
        if node not in index:
            visit(node)
    return loops


@pytest.mark.parametrize("path", _engine_modules_outside_gl(), ids=lambda p: str(p.relative_to(ROOT)))
def test_only_cloudcore_gl_imports_an_opengl_library(path):
    gl_imports = sorted(name for name in imported_modules(path) if name.split(".")[0] in GL_LIBRARIES)
    assert not gl_imports, f"{path.relative_to(ROOT)} imports {gl_imports}: OpenGL belongs in cloudcore/gl"


@pytest.mark.parametrize("name", MODEL_MODULES)
def test_the_scene_model_imports_no_feature(name):
    engine_imports = {m for m in imported_modules(ENGINE / name) if m.split(".")[0] == "cloudcore"}
    assert engine_imports <= set(MODEL_MAY_IMPORT), f"cloudcore/{name} imports {sorted(engine_imports)}"


def test_every_part_of_the_engine_has_a_layer():
    parts = {part_of(_module_name(path)) for path in _engine_modules()} - {None}
    assert parts <= set(LAYER_OF), f"not in LAYERS: {sorted(parts - set(LAYER_OF))}"
    assert set(LAYER_OF) <= parts, f"in LAYERS but not in the engine: {sorted(set(LAYER_OF) - parts)}"
    assert sum(map(len, LAYERS)) == len(LAYER_OF), "a part named in two layers"


@pytest.mark.parametrize("path", _engine_modules(), ids=lambda p: str(p.relative_to(ROOT)))
def test_no_import_runs_up_the_layers(path):
    part = part_of(_module_name(path))
    if part is None:
        return
    level = LAYER_OF[part]
    upward = sorted(m for m in imported_modules(path) if LAYER_OF.get(part_of(m), -1) > level)
    assert not upward, f"{path.relative_to(ROOT)} (layer {level}, {part}) imports {upward} from a layer above"


def test_no_parts_of_the_engine_import_each_other():
    loops = import_loops(_part_imports())
    assert not loops, f"parts of the engine that import each other, roundabout or not: {loops}"


def test_the_layer_check_sees_an_opengl_import(tmp_path):
    module = tmp_path / "m.py"
    module.write_text("def f():\n    from OpenGL import GL\n    import cloudcore.light.shading\n")
    assert imported_modules(module) == {"OpenGL", "cloudcore.light.shading"}


def test_the_loop_check_sees_a_roundabout_loop():
    imports = {"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}
    assert import_loops(imports) == [["a", "b", "c"]]
    assert part_of("cloudcore.lod.plan.planner") == "lod" and part_of("cloudcore") is None

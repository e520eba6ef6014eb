"""The layers of docs/architecture.md, read from the imports.

OpenGL only in cloudcore/gl; a scene model that depends on no feature.
"""

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
ENGINE = ROOT / "cloudcore"
GL_LIBRARIES = ("OpenGL", "pyrender", "imgui_bundle", "glfw")
#: the scene model: records only, so every feature may read them and none is needed to make one
MODEL_MODULES = ("scene.py", "cloud_records.py")
MODEL_MAY_IMPORT = ("cloudcore.cloud_records", "cloudcore.errors")


def imported_modules(path: Path) -> set[str]:
    """Every module `path` imports, absolute, at any depth of its code (function-level imports too)."""
    names = set()
    for node in ast.walk(ast.parse(path.read_text(), filename=str(path))):
        if isinstance(node, ast.Import):
            names.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            names.add(node.module)
    return names


def _engine_modules_outside_gl():
    return [p for p in sorted(ENGINE.rglob("*.py")) if (ENGINE / "gl") not in p.parents]


@pytest.mark.parametrize("path", _engine_modules_outside_gl(), ids=lambda p: str(p.relative_to(ROOT)))
def test_only_cloudcore_gl_imports_an_opengl_library(path):
    gl_imports = sorted(name for name in imported_modules(path) if name.split(".")[0] in GL_LIBRARIES)
    assert not gl_imports, f"{path.relative_to(ROOT)} imports {gl_imports}: OpenGL belongs in cloudcore/gl"


@pytest.mark.parametrize("name", MODEL_MODULES)
def test_the_scene_model_imports_no_feature(name):
    engine_imports = {m for m in imported_modules(ENGINE / name) if m.split(".")[0] == "cloudcore"}
    assert engine_imports <= set(MODEL_MAY_IMPORT), f"cloudcore/{name} imports {sorted(engine_imports)}"


def test_the_layer_check_sees_an_opengl_import(tmp_path):
    module = tmp_path / "m.py"
    module.write_text("def f():\n    from OpenGL import GL\n    import cloudcore.light.shading\n")
    assert imported_modules(module) == {"OpenGL", "cloudcore.light.shading"}

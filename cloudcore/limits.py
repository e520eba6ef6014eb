"""What the renderer can draw, checked where a scene comes in: when a file is loaded and when the editor changes it.

The GL side has hard limits of its own (a shader array, the kinds of terrain
it can mesh, integer cell numbers); a scene past one used to load and then end
in a traceback from the renderer.  The limits live here, on the pure side (no
OpenGL import), so the GL code takes its constants from this module and the
scene loader (`cloudcore.scenefile`: one line naming file and field, exit 2)
and the editor (`app.editor.Editor.edit`: a message, the scene kept) refuse
such a scene first.  docs/scene-format.md lists them.
"""

from __future__ import annotations

from cloudcore.artist.artist_shading import default_group_size, shading_grid_fits
from cloudcore.light.lighting import active_lights

#: lights that shine on clouds at once: the compute shader keeps one incident term per light
#: per particle (`incident[MAX_LIGHTS]` in gl/shaders/splat_shade.comp.glsl)
MAX_LIGHTS = 8
#: the terrain kinds the world pass can draw (gl/world.py meshes heightfields only)
DRAWN_TERRAIN_KINDS = ("heightfield",)
#: the largest side of a frame in pixels (llvmpipe's and most GPUs' largest renderbuffer)
MAX_FRAME_SIDE = 16384


def scene_limit_problems(scene, unchanged=None) -> list[tuple[str, str]]:
    """(field, problem) for each limit `scene` is past, fields as the scene file names them.

    `unchanged`: a scene whose clouds, where they are the very same objects, need
    no second look (the editor checks every edit; most leave most clouds alone).
    """
    problems = []
    if scene.lighting.lights:
        shining = len(active_lights(scene.lighting.lights))
        if shining > MAX_LIGHTS:
            problems.append(
                (
                    "lighting.lights",
                    f"at most {MAX_LIGHTS} lights can shine on clouds at once, "
                    f"the scene has {shining} (lights of intensity 0 or black do not count)",
                )
            )
    if scene.terrain is not None and scene.terrain.kind not in DRAWN_TERRAIN_KINDS:
        problems.append(
            (
                "terrain.kind",
                f"the renderer draws {' or '.join(DRAWN_TERRAIN_KINDS)} terrain only, not {scene.terrain.kind!r}",
            )
        )
    previous = {id(cloud) for cloud in unchanged.clouds} if unchanged is not None else set()
    for i, cloud in enumerate(scene.clouds):
        if cloud.artist is None or not len(cloud.particles) or id(cloud) in previous:
            continue
        size = cloud.shading_group_size or default_group_size(cloud.radii)
        if not shading_grid_fits(cloud.centres, size):
            field = "shading_group_size" if cloud.shading_group_size else "particles"
            problems.append(
                (
                    f"clouds[{i}].{field}",
                    f"shading groups of {size:g} m are too small for a cloud this "
                    "large (more than 2**53 groups across)",
                )
            )
    return problems

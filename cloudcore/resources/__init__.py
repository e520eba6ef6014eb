"""The files cloudview reads at run time, shipped inside the package: the built-in scenes and the sprite atlas.

They are found with `importlib.resources`, so an installed wheel finds them as
an editable checkout does (`pyproject.toml` declares them as package data).
Scene files name their particle files relative to themselves, so they are
handed out as file-system paths; pip always installs a package as files.
"""

from __future__ import annotations

from importlib.resources import files
from pathlib import Path


def resource_path(*parts: str) -> Path:
    """The packaged file cloudcore/resources/PARTS... as a path on the file system."""
    resource = files(__name__).joinpath(*parts)
    if not isinstance(resource, Path):
        raise RuntimeError(f"cloudview's resources must be installed as files, not in an archive ({resource})")
    return resource


#: the default scene (`cloudview` and `cloudview render` with no scene), after Harris 2002, figure 3
DEFAULT_SCENE = resource_path("scenes", "valley.toml")
#: Wang's cloud sprite sheet (`scripts/make_sprite_atlas.py` regenerates it)
ATLAS = resource_path("sprites", "atlas.png")
#: a cumulus field 100 km across (`[cloud_field]`, Yusov's nested grid) with a flight through and above it
CUMULUS_FIELD = resource_path("scenes", "cumulus_field.toml")

"""docs/scene-format.md names every key a scene file may hold (`scenefile.TABLE_KEYS`), each in its table's section."""

import re

import pytest

from cloudcore.scenes.files import TABLE_KEYS
from tests.conftest import ROOT

DOC = ROOT / "docs" / "scene-format.md"
#: tables documented inside another's section, or under a heading other than their TOML name
SECTION_OF = {"": "Top level", "lighting.lights": "`[lighting]`", "lighting.air": "`[lighting]`"}


def sections(text: str) -> dict[str, str]:
    """Each heading's text and what follows it up to the next heading of any level."""
    parts = re.split(r"^#{2,3} (.*)$", text, flags=re.M)
    return {heading: body for heading, body in zip(parts[1::2], parts[2::2])}


def section_of(table: str, documented: dict[str, str]) -> str:
    """The section of `table`: its explicit heading, else the heading that names it as `[t]`, `[[t]]` or `last`."""
    wanted = SECTION_OF.get(table)
    last = table.rsplit(".", 1)[-1]
    for heading, body in documented.items():
        names = (wanted,) if wanted else (f"`[{table}]`", f"`[[{table}]]`", f"`{last}`")
        if any(heading.startswith(name) for name in names):
            return body
    raise AssertionError(f"docs/scene-format.md has no section for the table {table!r}")


def undocumented_keys(table: str, text: str) -> list[str]:
    """The keys of `table` that the scene-format page `text` does not name in the table's section."""
    documented = sections(text)
    body = section_of(table, documented)
    sub_tables = {name.rsplit(".", 1)[-1] for name in TABLE_KEYS if name.startswith(f"{table}.") or not table}
    return [
        key
        for key in TABLE_KEYS[table]
        if f"| `{key}` |" not in body
        and f"`[[{table}.{key}]]`" not in body
        and not (key in sub_tables and section_of(f"{table}.{key}".lstrip("."), documented))
    ]


@pytest.mark.parametrize("table", sorted(TABLE_KEYS), ids=lambda t: t or "top level")
def test_every_key_of_a_table_is_a_row_of_its_section(table):
    missing = undocumented_keys(table, DOC.read_text())
    assert not missing, f"docs/scene-format.md does not document {table or 'top-level'} keys {missing}"


def test_a_row_taken_out_of_the_page_is_missed():
    text = DOC.read_text()
    row = next(line for line in text.splitlines() if line.startswith("| `fov_y_deg` |"))
    assert undocumented_keys("camera", text.replace(row + "\n", "", 1)) == ["fov_y_deg"]

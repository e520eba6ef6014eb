"""The docs' links and the code's references into the docs hold: every relative link of the README and docs/ names
a file that exists and, with an anchor, a heading of it (GitHub's anchors); every `docs/NAME.md#anchor` and
`docs/NAME.md, "Title"` in the code names a heading that is there.  Sections move as the docs are rewritten
(docs/performance.md by subject, its history in docs/journal.md), and a stale pointer is a reader sent nowhere."""

import re
from functools import cache
from pathlib import Path

from tests.conftest import ROOT

DOCS = ROOT / "docs"
MARKDOWN = [ROOT / "README.md", *sorted(DOCS.glob("*.md"))]
CODE = sorted(
    path
    for folder in ("cloudcore", "app", "scripts", "tests")
    for pattern in ("*.py", "*.glsl", "*.sh")
    for path in (ROOT / folder).rglob(pattern)
    if path != Path(__file__).resolve()  # its own docstring's examples
)

_LINK = re.compile(r"\]\(([^)\s]+)\)")
_REFERENCE = re.compile(r"(?:docs/)?([\w\-]+\.md)#([\w\-]+)")
_QUOTED = re.compile(r"(?:docs/)?([\w\-]+\.md),\s*\"([^\"]+)\"")
#: a comment's continuation between the words of a wrapped reference
_CONTINUATION = re.compile(r"\n\s*(?:#:?|//|\*)?\s*")


def slug(heading: str) -> str:
    """GitHub's anchor of a heading: lower case, punctuation dropped, spaces to hyphens."""
    return re.sub(r"[^\w\- ]", "", heading.strip().lower()).replace(" ", "-")


@cache
def headings(path: Path) -> tuple[frozenset, tuple]:
    """(the anchors, the titles) of a markdown file's headings, outside its code blocks."""
    anchors, titles, seen, in_code = set(), [], {}, False
    for line in path.read_text(encoding="utf-8").splitlines():
        if line.startswith("```"):
            in_code = not in_code
            continue
        heading = None if in_code else re.match(r"^#{1,6}\s+(.*?)\s*#*\s*$", line)
        if heading:
            anchor = slug(heading.group(1))
            repeats = seen.get(anchor, 0)
            seen[anchor] = repeats + 1
            anchors.add(anchor if repeats == 0 else f"{anchor}-{repeats}")
            titles.append(heading.group(1))
    return frozenset(anchors), tuple(titles)


def test_every_link_of_the_docs_reaches_its_file_and_heading():
    broken = []
    for page in MARKDOWN:
        text = page.read_text(encoding="utf-8")
        for link in _LINK.finditer(text):
            target = link.group(1)
            if re.match(r"^[a-z]+:", target):
                continue  # a web address
            path, _, anchor = target.partition("#")
            file = (page.parent / path).resolve() if path else page
            where = f"{page.relative_to(ROOT)}:{text.count(chr(10), 0, link.start()) + 1}: {target}"
            if not file.exists():
                broken.append(f"{where}: no such file")
            elif anchor and file.suffix == ".md" and anchor not in headings(file)[0]:
                broken.append(f"{where}: no heading of that anchor")
    assert not broken, "\n".join(broken)


def test_every_reference_of_the_code_into_the_docs_names_a_heading_there():
    broken, checked = [], 0
    for source in CODE:
        text = _CONTINUATION.sub(" ", source.read_text(encoding="utf-8", errors="replace"))
        for name, anchor in _REFERENCE.findall(text):
            checked += 1
            if not (DOCS / name).exists() or anchor not in headings(DOCS / name)[0]:
                broken.append(f"{source.relative_to(ROOT)}: {name}#{anchor}")
        for name, title in _QUOTED.findall(text):
            checked += 1
            title = " ".join(title.split())
            if not (DOCS / name).exists() or not any(t.startswith(title) for t in headings(DOCS / name)[1]):
                broken.append(f'{source.relative_to(ROOT)}: {name}, "{title}"')
    assert checked > 20
    assert not broken, "\n".join(broken)

"""Every relative link in the user docs leads somewhere: the file exists and, where the link
names a section (#anchor), the target has a heading with that anchor as GitHub renders it.

The docs cross-reference each other by section (commissioning.md -> hil.md#...); a heading
renamed in one file silently breaks the others' links, which no reader reports until lost.
"""
from __future__ import annotations

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
DOCS = sorted([ROOT / "README.md", *ROOT.glob("docs/*.md"), *ROOT.glob("host/docs/*.md"),
               *ROOT.glob("hil/*.md")])

LINK = re.compile(r"(?<!!)\[[^\]]*\]\(([^)\s]+)\)")   # [text](target), not images
IMAGE = re.compile(r"!\[[^\]]*\]\(([^)\s]+)\)")
HEADING = re.compile(r"^(#{1,6})\s+(.*?)\s*#*\s*$")
HTML_ANCHOR = re.compile(r"<a\s+(?:id|name)=\"([^\"]+)\"")
FENCE = re.compile(r"^\s*(```|~~~)")


def github_slug(heading: str) -> str:
    """The anchor GitHub gives a heading: markup dropped, lower case, punctuation other than
    '-' and '_' removed, each space a hyphen (runs are kept: 'a: `--x`' -> 'a---x')."""
    text = re.sub(r"\[([^\]]*)\]\([^)]*\)", r"\1", heading)   # a link's text only
    text = text.replace("`", "").replace("*", "")
    text = text.strip().lower()
    text = re.sub(r"[^\w\- ]", "", text)
    return text.replace(" ", "-")


def anchors(md: Path) -> set[str]:
    """Every anchor a markdown file offers: its headings' slugs (a repeated heading gets -1, -2,
    as GitHub numbers them) and explicit <a id/name> anchors."""
    out: set[str] = set()
    seen: dict[str, int] = {}
    in_fence = False
    for line in md.read_text(encoding="utf-8").splitlines():
        if FENCE.match(line):
            in_fence = not in_fence
            continue
        if in_fence:
            continue
        out.update(HTML_ANCHOR.findall(line))
        m = HEADING.match(line)
        if not m:
            continue
        slug = github_slug(m.group(2))
        n = seen.get(slug, 0)
        out.add(slug if n == 0 else f"{slug}-{n}")
        seen[slug] = n + 1
    return out


def links(md: Path) -> list[tuple[int, str]]:
    """(line number, target) of every link outside code blocks and code spans."""
    found: list[tuple[int, str]] = []
    in_fence = False
    for no, line in enumerate(md.read_text(encoding="utf-8").splitlines(), 1):
        if FENCE.match(line):
            in_fence = not in_fence
            continue
        if in_fence:
            continue
        prose = re.sub(r"`[^`]*`", "", line)
        found += [(no, t) for t in LINK.findall(prose)]
        found += [(no, t) for t in IMAGE.findall(prose)]
    return found


def broken_links(md: Path, root: Path = ROOT) -> list[str]:
    """What is wrong with md's relative links, one line each (paths relative to root)."""
    problems: list[str] = []
    for no, target in links(md):
        if re.match(r"^[a-z][a-z0-9+.-]*:", target):     # http:, https:, mailto:
            continue
        path_part, _, anchor = target.partition("#")
        dest = md if not path_part else (md.parent / path_part).resolve()
        if not dest.exists():
            problems.append(f"{md.relative_to(root)}:{no}: {target}: no such file")
            continue
        if anchor and dest.suffix == ".md" and anchor not in anchors(dest):
            problems.append(f"{md.relative_to(root)}:{no}: {target}: no section '#{anchor}' in "
                            f"{dest.relative_to(root)}")
    return problems


def test_the_slug_rule_matches_githubs() -> None:
    assert github_slug("A quieter valve: `--noise-limit`") == "a-quieter-valve---noise-limit"
    assert github_slug("Output (`--out DIR`)") == "output---out-dir"
    assert github_slug("Option 6: the hysteresis term (ppc.ref_ff_hyst)") == \
        "option-6-the-hysteresis-term-ppcref_ff_hyst"
    assert github_slug("See [the rig](rig.md)") == "see-the-rig"


def test_a_broken_link_is_found(tmp_path: Path) -> None:
    (tmp_path / "a.md").write_text("# Top\n\n## Two words\n\n[ok](#two-words) [bad](#three) "
                                   "[gone](b.md) [b](c.md#nope)\n```\n[in code](nowhere.md)\n```\n")
    (tmp_path / "c.md").write_text("# C\n")
    found = broken_links(tmp_path / "a.md", tmp_path)
    assert len(found) == 3, found
    assert "#three" in found[0] and "b.md: no such file" in found[1] and "#nope" in found[2]


@pytest.mark.parametrize("md", DOCS, ids=lambda p: str(p.relative_to(ROOT)))
def test_every_relative_link_resolves(md: Path) -> None:
    problems = broken_links(md)
    assert not problems, "\n".join(problems)

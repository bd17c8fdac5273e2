"""The pages for users: README.md stays a short guide (at most README_MAX_LINES lines), and
every link of it and of docs/ to a file of the repository, and to a heading there, is found."""

from __future__ import annotations

import re
from pathlib import Path

import pytest
from helpers.repo import REPO_ROOT

README = REPO_ROOT / "README.md"
README_MAX_LINES = 200
PAGES = [README, *sorted((REPO_ROOT / "docs").glob("*.md"))]
LINK = re.compile(r"\]\(([^)\s]+)\)")


def heading_anchors(page: Path) -> set[str]:
    """The anchors of a Markdown page's headings, as GitHub makes them."""
    anchors = set()
    for line in page.read_text().splitlines():
        heading = re.match(r"#+\s+(.*)", line)
        if heading:
            text = re.sub(r"[^\w\- ]", "", heading.group(1).strip().lower())
            anchors.add(text.replace(" ", "-"))
    return anchors


def broken_links(page: Path) -> list[str]:
    """The links of page to files of the repository that do not exist, or to headings they
    do not have; web addresses are not followed."""
    broken = []
    for target in LINK.findall(page.read_text()):
        if re.match(r"[a-z]+:", target):
            continue
        path, _, anchor = target.partition("#")
        linked = (page.parent / path).resolve() if path else page
        missing_heading = (anchor and linked.suffix == ".md"
                           and anchor not in heading_anchors(linked))
        if not linked.exists() or missing_heading:
            broken.append(target)
    return broken


@pytest.mark.timeout(10)
def test_the_readme_is_a_short_guide() -> None:
    lines = len(README.read_text().splitlines())
    assert lines <= README_MAX_LINES, f"README.md has {lines} lines: move detail into docs/"


@pytest.mark.timeout(10)
@pytest.mark.parametrize("page", PAGES, ids=lambda page: page.name)
def test_every_link_of_a_page_is_found(page) -> None:
    assert broken_links(page) == []


@pytest.mark.timeout(10)
def test_a_broken_link_is_told(tmp_path) -> None:
    (tmp_path / "other.md").write_text("# A heading\n")
    page = tmp_path / "page.md"
    page.write_text("[a](other.md#a-heading) [b](other.md#none) [c](gone.md) [d](#here) "
                    "[e](https://example.org/x)\n\n## Here\n")
    assert broken_links(page) == ["other.md#none", "gone.md"]

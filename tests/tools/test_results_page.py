"""docs/results.md is what tools/results_page.py makes of the JSON files in docs/."""

from __future__ import annotations

import shutil
import sys
from pathlib import Path

import pytest
from helpers.repo import REPO_ROOT

sys.path.insert(0, str(REPO_ROOT / "tools"))

import results_page

pytestmark = pytest.mark.timeout(30)


def test_shipped_page_is_up_to_date() -> None:
    assert results_page.main(["--check"]) == 0


def test_edited_page_fails_the_check(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    for path in (results_page.DOCS).glob("*.json"):
        shutil.copy(path, tmp_path / path.name)
    page = tmp_path / results_page.PAGE
    shutil.copy(results_page.DOCS / results_page.PAGE, page)
    assert results_page.main(["--check", "--docs", str(tmp_path)]) == 0
    page.write_text(page.read_text().replace("| 50 |", "| 51 |", 1))
    assert results_page.main(["--check", "--docs", str(tmp_path)]) == 1
    message = capsys.readouterr().err.strip()
    assert message.count("\n") == 0 and "out of date" in message

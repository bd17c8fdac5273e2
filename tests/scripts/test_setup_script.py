"""scripts/setup.sh: one clear message when a build tool is missing, nothing redone when
nothing changed."""

from __future__ import annotations

import os
import re
import shutil
import subprocess
from pathlib import Path

import pytest
from helpers.repo import REPO_ROOT


def path_without(hidden: re.Pattern[str], bin_dir: Path) -> str:
    """A PATH of one folder linking every executable on PATH except the hidden names."""
    bin_dir.mkdir()
    for folder in os.environ["PATH"].split(os.pathsep):
        if not os.path.isdir(folder):
            continue
        for name in os.listdir(folder):
            target = os.path.join(folder, name)
            link = bin_dir / name
            if hidden.fullmatch(name) or link.exists() or not os.access(target, os.X_OK):
                continue
            link.symlink_to(target)
    return str(bin_dir)


def fresh_checkout(root: Path) -> Path:
    """The files setup.sh reads, in a folder with no .venv and no build."""
    (root / "scripts").mkdir(parents=True)
    shutil.copy(REPO_ROOT / "scripts" / "setup.sh", root / "scripts" / "setup.sh")
    shutil.copy(REPO_ROOT / "requirements.txt", root / "requirements.txt")
    shutil.copytree(REPO_ROOT / "ros_ws" / "src", root / "ros_ws" / "src")
    return root


@pytest.mark.timeout(60)
@pytest.mark.parametrize(
    ("hidden", "message"),
    [
        (r"cmake", "setup.sh: error: cmake not found"),
        (r"(x86_64-linux-gnu-)?(cc|gcc|c\+\+|g\+\+)(-\d+)?", "setup.sh: error: no C compiler"),
    ],
)
def test_missing_build_tool_is_one_clear_message(hidden, message, tmp_path) -> None:
    checkout = fresh_checkout(tmp_path / "checkout")
    env = dict(os.environ, PATH=path_without(re.compile(hidden), tmp_path / "bin"))
    env.pop("VIRTUAL_ENV", None)
    result = subprocess.run(
        ["bash", str(checkout / "scripts" / "setup.sh")],
        capture_output=True,
        text=True,
        env=env,
        timeout=50,
    )
    print(result.stderr)
    assert result.returncode == 1
    assert result.stderr.strip().splitlines() == [result.stderr.strip()]  # one line
    assert result.stderr.startswith(message)
    assert not (checkout / ".venv").exists(), "it must stop before installing anything"


@pytest.mark.timeout(60)
def test_second_run_with_nothing_changed_redoes_nothing() -> None:
    result = subprocess.run(
        [str(REPO_ROOT / "scripts" / "setup.sh")], capture_output=True, text=True, timeout=50
    )
    assert result.returncode == 0, result.stderr
    assert result.stderr.strip() == ("setup.sh: the workspace is up to date (a shell of your "
                                     "own gets it with: source scripts/env.sh)")

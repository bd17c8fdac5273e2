"""The campaigns' cache cannot be turned against its user: an entry is unpickled only when
its HMAC under the user's key holds; a tampered, torn or foreign entry is recomputed with
one warning naming it, and the results are the same; the key is the user's alone (0600)."""

from __future__ import annotations

import logging
import os
import pickle
import stat
from pathlib import Path

import pytest
from uav_fault_estimator.campaigns.campaign import (
    ENTRY_MAGIC,
    CampaignOptions,
    TaskCache,
    cache_key,
    cache_key_path,
    run_campaign,
)

TASKS = [1, 2, 3]


def square(task: int) -> int:
    return task * task


class RunsCode:
    """Unpickled, it creates its marker file: what a planted entry would do."""

    def __init__(self, marker: Path) -> None:
        self.marker = marker

    def __reduce__(self):
        return Path.touch, (self.marker,)


@pytest.fixture
def cached(tmp_path: Path) -> tuple[CampaignOptions, TaskCache]:
    """Options with a cache in tmp_path, filled by one run; the cache of square."""
    options = CampaignOptions(workers=0, cache_dir=tmp_path / "cache", progress=False)
    assert run_campaign(square, TASKS, "fill", options).computed == len(TASKS)
    return options, TaskCache(options.cache_dir, square)


@pytest.mark.timeout(30)
def test_a_planted_pickle_is_never_run_and_its_task_is_recomputed(cached, tmp_path, caplog):
    options, cache = cached
    marker = tmp_path / "ran"
    planted = pickle.dumps(RunsCode(marker))
    entry = cache.path(TASKS[0])
    headers = entry.read_bytes()[:len(ENTRY_MAGIC) + 32]
    for forged in (planted, ENTRY_MAGIC + bytes(32) + planted, headers + planted):
        entry.write_bytes(forged)  # bare; with a made-up tag; with another content's tag
        with caplog.at_level(logging.WARNING):
            result = run_campaign(square, TASKS, "again", options)
        assert not marker.exists()
        assert (result.results, result.computed, result.cached) == ([1, 4, 9], 1, 2)
        assert [record.getMessage() for record in caplog.records] == [
            f"cache entry {entry} fails its check (not written with your key, or changed "
            "since): recomputed"]
        caplog.clear()


@pytest.mark.timeout(30)
def test_a_torn_entry_or_another_tasks_is_recomputed_once(cached, caplog):
    options, cache = cached
    torn, swapped = cache.path(TASKS[1]), cache.path(TASKS[2])
    torn.write_bytes(torn.read_bytes()[:20])  # a copy cut short
    swapped.write_bytes(cache.path(TASKS[0]).read_bytes())  # a valid entry, another task's
    with caplog.at_level(logging.WARNING):
        result = run_campaign(square, TASKS, "again", options)
    assert (result.results, result.computed, result.cached) == ([1, 4, 9], 2, 1)
    assert len(caplog.records) == 2 and all("fails its check" in r.getMessage()
                                            for r in caplog.records)
    again = run_campaign(square, TASKS, "after", options)  # the recomputed entries stored
    assert (again.results, again.computed, again.cached) == ([1, 4, 9], 0, 3)


@pytest.mark.timeout(30)
def test_the_key_is_made_for_the_user_alone_and_one_open_to_others_is_replaced(caplog):
    path = cache_key_path()
    assert path.is_relative_to(os.environ["XDG_CONFIG_HOME"])  # the session's, not ~/.config
    key = cache_key()
    assert len(key) == 32 and cache_key() == key
    assert stat.S_IMODE(path.stat().st_mode) == 0o600
    path.chmod(0o644)
    with caplog.at_level(logging.WARNING):
        replaced = cache_key()
    assert replaced != key and stat.S_IMODE(path.stat().st_mode) == 0o600
    assert "open to others (mode 644): replaced" in caplog.text

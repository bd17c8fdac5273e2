"""Campaigns: one function over many independent tasks (a flight, a log), in this process, on
local worker processes or on a Dask cluster of several machines, with each task's result
cached on disk, failures reported and the campaign going on, and a progress bar.

Execution is Dask distributed's (`dask[distributed]`): a LocalCluster of `workers`
processes of one thread each on 127.0.0.1, or the scheduler at `cluster`
(tls://HOST:8786 with the certificates of `tls_certs`, cluster_security.py; plain tcp://
on this machine only, unless `insecure_cluster`), whose workers run this checkout's code
(docs/performance.md says how to start them). A worker that dies has its tasks redone on
another (Dask's own). Each task is pure: its result depends on the task and the code alone,
so the results are the serial run's bit for bit and a cached one is as good as a new one.

The cache: `cache_dir/<code version>/<task key>.pkl`, the code version a hash of the
project's packages (Python modules and their data: aircraft, scenarios, calibrations) and of
the file defining the function, the task key a hash of the pickled function (by reference)
and the pickled task. A campaign computes only the tasks without a cached result, and stores
each result as it arrives, so an interrupted campaign resumes where it stopped. Unpickling
runs code, and a cache folder may be shared (a team's disk, a CI cache): each entry carries
an HMAC-SHA256 of its name and contents under the user's own key (cache_key_path, 0600),
checked before anything is unpickled. An entry that fails the check, is cut short or does
not load is recomputed with one warning naming it: never trusted, never fatal.
"""

from __future__ import annotations

import argparse
import functools
import hashlib
import hmac
import inspect
import logging
import os
import pickle
import secrets
import stat
import sys
import time
import traceback
from collections.abc import Callable, Iterator, Sequence
from contextlib import ExitStack
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, NamedTuple

import cloudpickle
import dask.config
from distributed import Client, LocalCluster, as_completed
from tqdm import tqdm
from uav_common.package_data import share_dir

from uav_fault_estimator.campaigns.cluster_security import (
    INSECURE_WARNING,
    ClusterAddressError,
    cluster_access,
)

# The packages whose code and data a task's result may depend on.
CODE_PACKAGES = ("uav_common", "uav_aircraft", "uav_sim", "uav_fault_estimator")
PICKLE_PROTOCOL = 5
LOCALHOST = "127.0.0.1"
# Local workers' housekeeping made rare: Dask's defaults (the event loop's health checked
# every 20 ms, a sampling profiler every 10 ms, memory every 100 ms) share a worker's one
# core with its flight; measured on 12 detectability flights on 2 workers: 1.62-1.77 times
# the serial speed with the defaults, 1.89-1.90 with these.
QUIET_WORKERS = {
    "distributed.admin.tick.interval": "1s",
    "distributed.worker.profile.enabled": False,
    "distributed.worker.memory.monitor-interval": "1s",
    "distributed.admin.system-monitor.interval": "5s",
}
PROGRESS_AFTER_S = 2.0  # a campaign shows its progress bar once it has run this long [s]
_log = logging.getLogger(__name__)


@dataclass(frozen=True)
class CampaignOptions:
    """Where a campaign runs. workers: local processes (0: in this process, one task after
    the other); cluster: a Dask scheduler's address instead (its workers), tls_certs the
    folder of cluster_certs.py's certificates for a tls:// one, insecure_cluster to allow
    plain tcp:// off this machine (cluster_security.cluster_access); cache_dir: the
    results' cache (None: none); progress: a progress bar on stderr (for work that
    lasts)."""

    workers: int = field(default_factory=lambda: os.cpu_count() or 1)
    cluster: str | None = None
    cache_dir: Path | None = None
    progress: bool = True
    tls_certs: Path | None = None
    insecure_cluster: bool = False


@dataclass(frozen=True)
class TaskFailure:
    """A task that raised: its index, the task, the exception's type name and first line,
    and the whole traceback."""

    index: int
    task: Any
    kind: str
    message: str
    traceback: str

    @property
    def error(self) -> str:
        return f"{self.kind}: {self.message}"


@dataclass
class CampaignResult:
    """The results in the tasks' order (None where a task failed), the failures, and how
    many results were computed and how many read from the cache."""

    results: list
    failures: list[TaskFailure]
    computed: int
    cached: int
    wall_s: float

    def raise_failures(self) -> None:
        """CampaignFailedError naming every failed task, if any."""
        if self.failures:
            lines = [f"task {f.index} ({_short(f.task)}): {f.error}" for f in self.failures]
            raise CampaignFailedError(f"{len(self.failures)} of {len(self.results)} tasks failed "
                                 "(the others' results are cached with --cache):\n"
                                 + "\n".join(lines))


class CampaignFailedError(RuntimeError):
    """Tasks of a campaign raised: the message names each, a line per task."""


def exit_on_failed_tasks(main: Callable[[], int | None]) -> Callable[[], int]:
    """A script's main that, when tasks of a campaign failed or its cluster was refused,
    prints why (stderr) and returns 1 rather than ending in a traceback."""
    @functools.wraps(main)
    def guarded() -> int:
        try:
            return main() or 0
        except (CampaignFailedError, ClusterAddressError) as error:
            print(f"{Path(sys.argv[0]).name}: {error}", file=sys.stderr)
            return 1
    return guarded


class Campaign:
    """Where a campaign's tasks run, for one or several runs (a calibration's iterations):
    the Dask client, started at the first run that needs one and closed on leaving the
    `with` block."""

    def __init__(self, options: CampaignOptions = CampaignOptions()) -> None:
        self.options = options
        self._stack = ExitStack()
        self._client: Client | None = None

    def __enter__(self) -> Campaign:
        return self

    def __exit__(self, *_exception: object) -> None:
        self._stack.close()
        self._client = None

    def run(self, function: Callable[[Any], Any], tasks: Sequence,
            name: str) -> CampaignResult:
        """function(task) for every task (a module-level function, or a partial or
        picklable object of one); the results in the tasks' order. A task that raises is a
        TaskFailure; the others go on."""
        started = time.monotonic()
        cache = TaskCache(self.options.cache_dir, function) if self.options.cache_dir else None
        results: list = [None] * len(tasks)
        pending = []
        for index, task in enumerate(tasks):
            hit, value = cache.load(task) if cache else (False, None)
            if hit:
                results[index] = value
            else:
                pending.append(index)
        failures: list[TaskFailure] = []
        cached = len(tasks) - len(pending)
        with tqdm(total=len(tasks), initial=cached, desc=name, unit="task", file=sys.stderr,
                  disable=not self.options.progress, dynamic_ncols=True,
                  delay=PROGRESS_AFTER_S) as bar:
            bar.set_postfix(failed=0, cached=cached, refresh=False)
            for index, outcome in self._outcomes(function, tasks, pending):
                if isinstance(outcome, _Raised):  # counted on the bar, said at the end
                    failures.append(TaskFailure(index, tasks[index], *outcome))
                else:
                    results[index] = outcome
                    if cache:
                        cache.store(tasks[index], outcome)
                bar.update(1)
                bar.set_postfix(failed=len(failures), cached=cached, refresh=False)
        failures.sort(key=lambda failure: failure.index)
        return CampaignResult(results, failures, len(pending) - len(failures), cached,
                              time.monotonic() - started)

    def results(self, function: Callable[[Any], Any], tasks: Sequence, name: str) -> list:
        """run()'s results; CampaignFailedError naming every failed task once the others are
        done (and cached: a rerun computes only the failed ones)."""
        result = self.run(function, tasks, name)
        result.raise_failures()
        return result.results

    def _outcomes(self, function: Callable, tasks: Sequence,
                  pending: list[int]) -> Iterator[tuple[int, Any]]:
        """(index, result or _Raised) of each pending task, as they finish."""
        if not pending:
            return
        # no cluster to start for one task
        if self.options.cluster is None and (self.options.workers == 0 or len(pending) == 1):
            for index in pending:
                yield index, _call(function, tasks[index])
            return
        client = self.client()
        # pickled here, by cloudpickle: a function of a script or of a module registered to
        # go by value reaches workers (and a scheduler) that cannot import it
        pickled = cloudpickle.dumps(function)
        futures = {client.submit(_call_pickled, pickled, tasks[index], pure=False): index
                   for index in pending}
        for future in as_completed(futures):
            index = futures[future]
            if future.status == "error":  # the task's own errors are caught: a lost worker
                yield index, _raised(future.exception())
            else:
                yield index, future.result()
            future.release()

    def client(self) -> Client:
        """The Dask client, connected at the first call: to the cluster the options name, or
        to a LocalCluster of options.workers single-threaded processes (QUIET_WORKERS),
        every port of it (the dashboard's too) on 127.0.0.1. ClusterAddressError, before
        connecting, for a cluster address cluster_access refuses."""
        if self._client is None:
            options = self.options
            if options.cluster is not None:
                access = cluster_access(options.cluster, options.tls_certs,
                                        options.insecure_cluster)
                if access.insecure:
                    _log.warning(INSECURE_WARNING.format(address=access.address))
                self._client = self._stack.enter_context(
                    Client(access.address, security=access.security, timeout="30s"))
            else:
                self._stack.enter_context(dask.config.set(QUIET_WORKERS))
                cluster = self._stack.enter_context(LocalCluster(
                    n_workers=self.options.workers, threads_per_worker=1, processes=True,
                    host=LOCALHOST, dashboard_address=f"{LOCALHOST}:0",  # 127.0.0.1 alone
                    silence_logs=logging.ERROR))
                self._client = self._stack.enter_context(Client(cluster))
        return self._client


def run_campaign(function: Callable[[Any], Any], tasks: Sequence, name: str,
                 options: CampaignOptions = CampaignOptions()) -> CampaignResult:
    """One run of a Campaign of its own (Campaign.run)."""
    with Campaign(options) as campaign:
        return campaign.run(function, tasks, name)


class _Raised(NamedTuple):
    """What a task raised, as text (any exception, picklable or not)."""

    kind: str
    message: str
    traceback: str


def _raised(error: BaseException) -> _Raised:
    return _Raised(type(error).__name__, (str(error).splitlines() or [""])[0],
                   "".join(traceback.format_exception(error)))


def _call(function: Callable, task: Any) -> Any:
    """function(task), or _Raised."""
    try:
        return function(task)
    except Exception as error:
        return _raised(error)


def _call_pickled(pickled_function: bytes, task: Any) -> Any:
    """_call of a function cloudpickle pickled."""
    return _call(cloudpickle.loads(pickled_function), task)


def _short(task: Any, length: int = 120) -> str:
    """A task as one line, for messages: a scenario by its name and seed."""
    if hasattr(task, "name") and hasattr(task, "seed"):
        return f"scenario '{task.name}' seed {task.seed}"
    text = " ".join(repr(task).split())
    return text if len(text) <= length else text[:length - 3] + "..."


class TaskCache:
    """Results of one function's tasks on disk, for this code version, each entry
    ENTRY_MAGIC, its HMAC (key: cache_key()) and the pickled result."""

    def __init__(self, cache_dir: Path, function: Callable) -> None:
        self.function = pickle.dumps(function, protocol=PICKLE_PROTOCOL)  # by reference
        self.folder = Path(cache_dir) / code_version(function)
        self.key = cache_key()

    def path(self, task: Any) -> Path:
        digest = hashlib.sha256(self.function)
        digest.update(pickle.dumps(task, protocol=PICKLE_PROTOCOL))
        return self.folder / f"{digest.hexdigest()}.pkl"

    def load(self, task: Any) -> tuple[bool, Any]:
        """(True, the cached result) or (False, None): none there, or one that fails its
        check or does not load (said once, by name: it is recomputed)."""
        path = self.path(task)
        try:
            entry = path.read_bytes()
        except FileNotFoundError:
            return False, None
        header = len(ENTRY_MAGIC) + ENTRY_TAG_BYTES
        payload = entry[header:]
        if entry[:len(ENTRY_MAGIC)] != ENTRY_MAGIC or not hmac.compare_digest(
                entry[len(ENTRY_MAGIC):header], self._tag(path, payload)):
            _log.warning("cache entry %s fails its check (not written with your key, or "
                         "changed since): recomputed", path)
            return False, None
        try:
            return True, pickle.loads(payload)
        except Exception as error:  # signed by us, yet unreadable: a library moved on
            _log.warning("cache entry %s does not load (%s): recomputed", path, error)
            return False, None

    def store(self, task: Any, result: Any) -> None:
        """Written whole or not at all (a temporary file renamed)."""
        path = self.path(task)
        path.parent.mkdir(parents=True, exist_ok=True)
        payload = pickle.dumps(result, protocol=PICKLE_PROTOCOL)
        temporary = path.with_suffix(f".{os.getpid()}.tmp")
        temporary.write_bytes(ENTRY_MAGIC + self._tag(path, payload) + payload)
        temporary.replace(path)

    def _tag(self, path: Path, payload: bytes) -> bytes:
        """The HMAC of an entry: its name too, so that no entry stands in for another."""
        return hmac.new(self.key, path.name.encode() + b"\0" + payload, "sha256").digest()


ENTRY_MAGIC = b"uavfd-cache-1\n"
ENTRY_TAG_BYTES = 32  # HMAC-SHA256
CACHE_KEY_BYTES = 32


def cache_key_path() -> Path:
    """The user's cache key: $XDG_CONFIG_HOME (default ~/.config)/uav_fault_diagnostics/
    cache.key."""
    config = os.environ.get("XDG_CONFIG_HOME") or Path.home() / ".config"
    return Path(config) / "uav_fault_diagnostics" / "cache.key"


def cache_key() -> bytes:
    """The user's cache key, made at first use (CACHE_KEY_BYTES random bytes, mode 0600).
    A key others may read is no secret, and a file of another size no key: either is
    replaced by a new one (said once; entries written with the old one are recomputed)."""
    path = cache_key_path()
    try:
        mode = path.stat().st_mode
    except FileNotFoundError:
        return _new_cache_key(path)
    if mode & (stat.S_IRWXG | stat.S_IRWXO):
        problem = f"was open to others (mode {stat.S_IMODE(mode):o})"
    elif len(key := path.read_bytes()) == CACHE_KEY_BYTES:
        return key
    else:
        problem = "is not a key"
    _log.warning("cache key %s %s: replaced by a new one", path, problem)
    path.unlink()
    return _new_cache_key(path)


def _new_cache_key(path: Path) -> bytes:
    """A new key at path, mode 0600 from its creation and whole when it appears (linked
    from a temporary file); the key another process put there first, if one did."""
    path.parent.mkdir(parents=True, exist_ok=True, mode=0o700)
    temporary = path.with_name(f"{path.name}.{os.getpid()}.tmp")
    key = secrets.token_bytes(CACHE_KEY_BYTES)
    descriptor = os.open(temporary, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o600)
    with os.fdopen(descriptor, "wb") as file:
        file.write(key)
    try:
        os.link(temporary, path)
    except FileExistsError:
        key = path.read_bytes()
    finally:
        temporary.unlink()
    return key


def code_version(function: Callable) -> str:
    """A hash (16 hex digits) of every file of CODE_PACKAGES (modules, and the data they
    install: aircraft, scenarios, calibrations) and of the file defining function (or the
    function a partial or callable object wraps)."""
    digest = hashlib.sha256()
    roots = []
    for package in CODE_PACKAGES:
        module = sys.modules.get(package) or __import__(package)
        roots += [Path(module.__file__).parent, share_dir(package)]
    files = sorted(path for root in roots for path in Path(root).rglob("*")
                   if path.is_file() and "__pycache__" not in path.parts)
    inner = function.func if isinstance(function, functools.partial) else function
    source = inspect.getsourcefile(inner if inspect.isroutine(inner) else type(inner))
    for path in [*files, *([Path(source)] if source else [])]:
        digest.update(path.name.encode())
        digest.update(path.read_bytes())
    return digest.hexdigest()[:16]


def add_campaign_arguments(parser: argparse.ArgumentParser) -> None:
    """--workers, --cluster, --tls-certs, --insecure-cluster, --cache, --no-progress for a
    script that runs a campaign."""
    group = parser.add_argument_group("where the flights run (Dask)")
    group.add_argument("--workers", type=int, default=os.cpu_count() or 1,
                       help="local worker processes (default: the cores, %(default)s; 0: in "
                            "this process, one after the other)")
    group.add_argument("--cluster", metavar="tls://HOST:8786",
                       help="a running Dask scheduler to send the tasks to instead (tcp:// "
                            "only on this machine)")
    group.add_argument("--tls-certs", type=Path, metavar="DIR",
                       help="the cluster's certificates (scripts/cluster_certs.py), for a "
                            "tls:// --cluster")
    group.add_argument("--insecure-cluster", action="store_true",
                       help="allow a plain tcp:// --cluster on another machine: anyone who "
                            "can reach its scheduler can run code on its workers")
    group.add_argument("--cache", type=Path, metavar="DIR",
                       help="keep each task's result here, keyed by its inputs and the "
                            "code's version: a rerun computes only what is missing")
    group.add_argument("--no-progress", action="store_true", help="no progress bar")


def campaign_options(args: argparse.Namespace) -> CampaignOptions:
    """The options add_campaign_arguments' arguments give; ValueError for a negative
    --workers, ClusterAddressError (a ValueError) for a cluster cluster_access refuses,
    before anything connects."""
    if args.workers < 0:
        raise ValueError(f"--workers {args.workers}: 0 or more")
    if args.cluster is not None:
        cluster_access(args.cluster, args.tls_certs, args.insecure_cluster)
    elif args.tls_certs is not None or args.insecure_cluster:
        raise ClusterAddressError("--tls-certs and --insecure-cluster go with --cluster")
    return CampaignOptions(workers=args.workers, cluster=args.cluster, cache_dir=args.cache,
                           progress=not args.no_progress, tls_certs=args.tls_certs,
                           insecure_cluster=args.insecure_cluster)

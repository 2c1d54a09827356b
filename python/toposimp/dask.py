"""toposimp map with the engine's tiles run as Dask tasks.

    python3 -m toposimp.dask map INPUT -o OUTPUT --keep 10% [map options] [--scheduler tcp://host:8786]

runs `toposimp map` (the same options, messages, output files and exit statuses) with the
simplification cut at a level of its block hierarchy: every tile (a block of that level) is
simplified below it as a Dask task that holds only the tile's chains and control points, and the
levels above run here over what the tiles leave. Count targets (--keep, --keep-points,
--remove-points) run rounds: each round's budget is chosen here, over the whole map, and its
tiles are tasks. The output is byte for byte the one `toposimp map` writes, for any number of
workers (docs/distributed.md says why).

Without --scheduler, a LocalCluster of --workers processes runs the tasks. With one, start it and
its workers first, on every host that should work (Dask's own commands):

    dask scheduler                       # on one host: prints tcp://HOST:8786
    dask worker tcp://HOST:8786          # on each host (PYTHONPATH must reach this package)

Only the tasks' data travels (numpy arrays, through Dask: straight to the workers where they run
on this machine, else through the scheduler); the input and the output are read and written here.
A worker that dies has its tasks rerun elsewhere; the result is the same.

--levels runs each level in parts. With --first-round workers --kept-tiles, the live map stays on
the workers after the first round (each round's budget is selected there, and the levels above the
tiles run here over small subsets of it); a worker lost then has its tiles built again by Dask
from the input and the rounds' news. Both are chosen by themselves (--first-round auto, --kept-tiles
auto) when the map, then the live map, could not be held here. Not yet: a map bigger than this
process's memory in every case (the writing runs here).
"""
import argparse
import contextlib
import os
import signal
import sys

from toposimp import _launch, _toposimp

USAGE = """usage: python3 -m toposimp.dask map INPUT -o OUTPUT [toposimp map options]
                                   [--scheduler ADDRESS] [--workers N] [--tile-level T] [--tile-points N]
                                   [--task-threads N] [--local-budget N] [--first-round WHERE]
                                   [--send-input] [--worker-malloc WHICH] [--top-runs N] [--kept-tiles [WHEN]]

toposimp map's simplification run as Dask tasks, the output identical to toposimp map's.

Dask options:
  --scheduler ADDRESS  a running Dask scheduler (tcp://host:8786); default: a LocalCluster here
  --workers N          the LocalCluster's worker processes (default: the cores here)
  --tile-level T       the block level cut into tasks (default: the coarsest whose biggest tile
                       holds at most --tile-points vertices and control points)
  --tile-points N      see --tile-level (default 1000000, or less where a worker's memory limit
                       would not hold such a tile for each of its Dask threads in half of it)
  --task-threads N     threads each task's engine uses (default: a host's cores shared among the
                       Dask threads of its workers, at least 1: 1 for the default LocalCluster
                       of a worker a core, 2 for one worker on 2 cores); a task of at least as
                       many groups of tiles runs them side by side, a thread each
  --local-budget N     a round of a count target that removes fewer than N vertices runs here,
                       whole, not as tasks (default 4000000, about a second of one core here,
                       less than cutting the live map into tiles again; 0: every round as tasks)
  --first-round WHERE  where the first round's tiles are built: 'here' (by the whole map's engine
                       in this process), 'workers' (the map cut into tiles, searched for
                       crossings, queued and its budget selected on the workers; this process
                       never holds an engine over the whole map), or 'auto' (default): 'workers'
                       where the input is read by parts (below) and, read here whole, could take
                       more than half the memory this process may still take (about 5 times its
                       size on disk: a file's, or a folder's files'; -v says what it found), else
                       'here'. With 'workers',
                       Shapefiles (a .shp, or a folder of them) of PolyLines or of polygons,
                       GeoPackages and FlatGeobufs (a .fgb or a folder of them,
                       with their index of features) of (Multi)LineString and (Multi)Polygon
                       layers, Z or M too, written at one target without --decimals,
                       --precision, --levels or --quantize
                       are read by parts on the workers (2D point layers among them
                       are read here, as control points): this process then never holds their
                       vertices, and the input files must be at the same absolute paths,
                       unchanged, on every worker. Other inputs are read here.
  --send-input         with --first-round workers: read the input here and send the workers its
                       parts (for workers that cannot see the input)
  --worker-malloc WHICH  the allocator of the LocalCluster's workers: 'auto' (default: jemalloc
                       where libjemalloc.so.2 is installed, Debian's libjemalloc2, else glibc's),
                       'jemalloc' or 'glibc'. A worker runs task after task, each allocating
                       its tile's arrays afresh: jemalloc keeps freed memory for the next task
                       where glibc gives big blocks back to the kernel, to be faulted in again
                       (GSHHG at 10 % on 2 workers here: 7.4-7.5 s against 8.7-9.9 s). Workers started by
                       you (--scheduler) use what their environment says, e.g.
                       LD_PRELOAD=libjemalloc.so.2 MALLOC_CONF=thp:always dask worker ...
                       (The LocalCluster's workers also run without Dask's profiler, which
                       serves a dashboard they do not have; -v says so.)
  --top-runs N         the levels above the tiles over a small part of the live map, not all
                       of it: runs of N live vertices on either side of their candidates, the
                       points near them (N twice as long while they fall short; 0, the default:
                       the whole live map). The same output; the step towards a live map that
                       stays on the workers (docs/distributed.md)
  --kept-tiles [WHEN]  with --first-round workers: the first round's tiles stay on the workers
                       for the rounds after, told what each round changed, and the levels above
                       the tiles run over subsets gathered from them: this process never holds
                       the live map (a byte a vertex for the result). The same output, also
                       when a worker is lost (Dask builds its tiles again); slower (GSHHG at
                       10 % on 2 workers: 10.4 s against 4.9 s without it). WHEN: 'yes' (the
                       default of --kept-tiles alone), 'no', or 'auto' (the default without
                       it): yes when the live map after the first round could take more than
                       half the memory this process may still take (at most every vertex of the
                       map, about 100 bytes each; the machine's available memory, or less under
                       a cgroup limit; -v says what it found)

Every other option is toposimp map's: run 'toposimp map --help' (or man toposimp).
"""


# A round of a count target that removes fewer vertices than this runs in the command's process,
# whole (about a second of one core there): as tasks, every live vertex would be cut into tiles,
# sent and indexed again first, which costs more (GSHHG at 10 % on 2 workers: its second round,
# 2.1 M removals among 3 M live vertices, took 0.9 s as tasks, the whole run 6.3-6.6 s against
# 5.6-5.7 s with it here).
LOCAL_BUDGET = 4_000_000


def _run_groups(groups, plan, options):
    """A Dask task: groups of tiles, each through the levels below the tile level; side by side,
    a thread each, when there are at least as many as the task's threads (run_tile_groups)."""
    from toposimp import _toposimp as engine
    if type(groups) is tuple and groups and groups[0] is _given:  # (a Dask that hands nested tasks over as they are)
        groups = groups[1]
    return engine.run_tile_groups(list(groups), plan, options) if groups else []


def _given(value):
    """`value`. A task's argument written `(_given, value)` is a task nested in it: Dask then sends
    the whole task through its serializers, which carry numpy arrays out of band, as they are,
    instead of pickling the arguments into one bytes object (a copy of every array, which Dask then
    scans for `__main__`). With _tiles_uncompressed, GSHHG at 10 % on 2 workers: 4.36 -> 4.17 s
    (medians of 6 alternating runs)."""
    return value


@contextlib.contextmanager
def _tiles_uncompressed():
    """Dask's compression of what this client sends off while a round's tiles go, unless the user
    chose one (distributed.comm.compression is "auto" by default: lz4 where installed). Serialized
    out of band (_given), the tiles' arrays would be compressed, and coordinates compress badly:
    GSHHG's first round, 217 MB of tiles as they were then (178 MB since their ids go as runs), to
    166 MB, for 0.29 s of this process's CPU: about what sending the difference takes over a 1 Gb/s
    network (0.4 s), far more than over 10 Gb/s or loopback. On a slower network, set it (e.g.
    DASK_DISTRIBUTED__COMM__COMPRESSION=lz4)."""
    import dask.config
    import distributed  # noqa: F401 (its defaults loaded first: leaving dask.config.set removes the keys it added)

    if dask.config.get("distributed.comm.compression") != "auto":
        yield
        return
    with dask.config.set({"distributed.comm.compression": False}):
        yield


def _batches(points, workers):
    """The round's groups (their sizes in points) as tasks: the biggest first, so that the round
    does not wait at its end on one big task begun late; the small ones together, up to the
    biggest group's size or a share of the round (whichever is smaller), so that Dask's own cost
    per task (a few milliseconds of CPU over the processes) stays small against the work. A task
    never holds more than the biggest group: the workers' memory bound holds."""
    if not points:
        return []
    order = sorted(range(len(points)), key=lambda k: (-points[k], k))
    limit = min(points[order[0]], -(-sum(points) // (2 * max(1, workers))))
    batches, current, size = [], [], 0
    for k in order:
        if current and size + points[k] > limit:
            batches.append(current)
            current, size = [], 0
        current.append(k)
        size += points[k]
    batches.append(current)
    return batches


class _Progress:
    def __init__(self, quiet):
        self.quiet = quiet
        self.terminal = sys.stderr.isatty()
        self.round = 1
        self.tile_level = 0

    def tiles(self, done, total):
        self.stage(f"round {self.round}, tiles of level {self.tile_level}", done, total)

    def stage(self, what, done, total):
        if self.quiet:
            return
        line = f"toposimp.dask: {what}: {done} of {total} tasks done"
        if self.terminal:
            sys.stderr.write("\r" + line + ("\n" if done == total else ""))
        elif done == total:
            sys.stderr.write(line + "\n")
        sys.stderr.flush()


def _split_arguments(argv):
    """(Dask options, toposimp map's arguments)."""
    parser = argparse.ArgumentParser(add_help=False, allow_abbrev=False)
    parser.add_argument("--scheduler")
    parser.add_argument("--workers", type=int)
    parser.add_argument("--tile-level", type=int, default=-1)
    parser.add_argument("--tile-points", type=int, default=1_000_000)
    parser.add_argument("--task-threads", type=int)
    parser.add_argument("--local-budget", type=int, default=LOCAL_BUDGET)
    parser.add_argument("--first-round", choices=("workers", "here", "auto"), default="auto")
    parser.add_argument("--send-input", action="store_true")
    parser.add_argument("--worker-malloc", choices=("auto", "jemalloc", "glibc"), default="auto")
    parser.add_argument("--top-runs", type=int, default=0)
    parser.add_argument("--kept-tiles", nargs="?", choices=("yes", "no", "auto"), const="yes", default="auto")
    options, rest = parser.parse_known_args(argv)
    if options.workers is not None and options.workers < 1:
        parser.error("--workers must be at least 1")
    if options.task_threads is not None and options.task_threads < 1:
        parser.error("--task-threads must be at least 1")
    if options.tile_points < 1:
        parser.error("--tile-points must be at least 1")
    if options.local_budget < 0:
        parser.error("--local-budget must be 0 or more")
    if not 0 <= options.top_runs < 2**31:
        parser.error("--top-runs must be 0 or more, under 2^31")
    if options.kept_tiles == "yes" and options.first_round == "here":
        parser.error("--kept-tiles needs --first-round workers")
    options.kept_tiles = {"yes": True, "no": False, "auto": "auto"}[options.kept_tiles]
    return options, rest


def run(map_arguments, *, scheduler=None, workers=None, tile_level=-1, tile_points=1_000_000, task_threads=None,
        local_budget=None, client=None, quiet=False, on_progress=None, first_round="auto", send_input=False,
        worker_malloc="auto", top_runs=0, kept_tiles="auto"):
    """Runs `toposimp map MAP_ARGUMENTS` with the tiles on Dask; returns the exit status.

    `client`: a distributed.Client to use (else one is made from `scheduler`, or a LocalCluster
    of `workers` processes, when the first tasks are ready — not for a run that stops on bad usage
    or input before — and closed at the end). A count target's round that removes fewer
    than `local_budget` vertices (default LOCAL_BUDGET) runs here, whole. `on_progress(done,
    total)`: called as the tile tasks finish. `task_threads`: the threads of each task's engine
    (default: task_threads_for the workers). `first_round`: where the first round's tiles are
    built, "workers", "here" (the whole map's engine here) or "auto" (default: "workers" where the
    input is read by parts and could not be held here whole, _input_too_big). With "workers", the first round's
    tasks read their parts of the input themselves where its format allows (Shapefiles,
    GeoPackages and FlatGeobufs of lines or polygons, written through GDAL: the input must then be at
    the same absolute path, unchanged, on every worker), and this process never holds the input's
    vertices; `send_input` sends them the parts from here instead. `worker_malloc`: the allocator
    of the LocalCluster's workers, "auto" (jemalloc where installed), "jemalloc" or "glibc"
    (_worker_malloc). `top_runs` (> 0): the levels above the tiles run over a subset of the live
    map, runs of that many vertices around their candidates (MapInParts::top_subset): the same
    output. `kept_tiles` (with first_round="workers"): True, the first round's tiles stay on the
    workers for the rounds after, and this process never holds the live map (map::KeptTiles): the
    same output; "auto" (default), so when the live map after the first round could take more
    than half the memory this process may still take (_memory_here, _Tasks._keep_tiles); False,
    never."""
    if first_round not in ("workers", "here", "auto"):
        raise ValueError(f"first_round must be 'workers', 'here' or 'auto', not {first_round!r}")
    if kept_tiles not in (True, False, "auto"):
        raise ValueError(f"kept_tiles must be True, False or 'auto', not {kept_tiles!r}")
    if kept_tiles is True and first_round == "here":
        raise ValueError("kept_tiles needs first_round='workers'")
    if first_round == "auto" and (kept_tiles is True or send_input):
        first_round = "workers"  # (what they need)
    if local_budget is None:
        local_budget = LOCAL_BUDGET
    workers_environment = local_worker_environment(worker_malloc, os.environ) if client is None and not scheduler else {}
    verbose = any(a == "--verbose" or (len(a) > 1 and a[0] == "-" and set(a[1:]) == {"v"}) for a in map_arguments)
    progress = _Progress(quiet)
    if verbose:
        sys.stderr.write(f"toposimp.dask: debug: this process's glibc tunables: {os.environ.get('GLIBC_TUNABLES') or '(none)'}\n")
    own = {}  # the client and LocalCluster made here, if any
    connecting = _Connecting(scheduler) if client is None else None

    def connected():
        if client is not None:
            return client
        if "client" not in own:
            if scheduler:
                own["client"] = connecting.take()
            else:
                from distributed import Client, LocalCluster

                # Nothing on the terminal but the run's own lines (none with -q):
                # - a new worker process first purges the folders of workers that died without
                #   cleaning up (a killed run's) and says so at INFO, before LocalCluster quiets its
                #   logs to warnings: the worker processes, spawned here, start with Dask's logs at
                #   warnings (warnings still show);
                # - the scheduler, without a dashboard, still serves HTTP (health, metrics), on
                #   Dask's dashboard port unless told otherwise, with a warning when another
                #   cluster's dashboard holds it: any free port.
                import dask.config

                with _environment(DASK_LOGGING__DISTRIBUTED="warning", **workers_environment), \
                        dask.config.set(local_worker_config(os.environ)):
                    own["cluster"] = LocalCluster(n_workers=workers or os.cpu_count(), threads_per_worker=1, processes=True,
                                                  dashboard_address=None, scheduler_kwargs={"dashboard_address": ":0"})
                own["client"] = Client(own["cluster"])
                if verbose:
                    found = sorted(set(own["client"].run(_malloc_here).values()))
                    profiled = sorted(set(own["client"].run(_profiled_here).values()))
                    sys.stderr.write(f"toposimp.dask: debug: the LocalCluster's workers' malloc: {', '.join(found)} "
                                     f"(--worker-malloc {worker_malloc}); Dask's profiler: {', '.join(profiled)}\n")
        return own["client"]

    run_groups = _tasks(connected, task_threads, progress, on_progress, first_here=first_round == "here", top_runs=top_runs,
                        kept=kept_tiles, verbose=verbose, by_parts_only=first_round == "auto")
    try:
        status, out, err = _toposimp.run_command(["map", *map_arguments], run_groups, tile_level,
                                                 lambda: fitting_tile_points(connected(), tile_points), local_budget, None,
                                                 sys.stderr.isatty(), _main_thread(),
                                                 input_on_workers=first_round != "here" and not send_input,
                                                 in_file_if=(lambda size: _input_too_big(size, verbose)) if first_round == "auto" else None)
        if verbose and any(run_groups.waves.values()):
            sys.stderr.write(f"toposimp.dask: debug: the kept tiles' questions: {run_groups.waves['straight']} waves asked straight of "
                             f"the workers, {run_groups.waves['through tasks']} through tasks\n")
    finally:
        if connecting is not None:
            connecting.close()
        if "client" in own:
            own["client"].close()
        if "cluster" in own:
            own["cluster"].close()
    sys.stdout.write(out)
    sys.stderr.write(err)
    return status


@contextlib.contextmanager
def _environment(**variables):
    """These environment variables set (for the processes started meanwhile), then as they were."""
    before = {name: os.environ.get(name) for name in variables}
    os.environ.update(variables)
    try:
        yield
    finally:
        for name, value in before.items():
            if value is None:
                os.environ.pop(name, None)
            else:
                os.environ[name] = value


def _worker_malloc(which, environ):
    """The environment the LocalCluster's workers get for their allocator `which` ("auto",
    "jemalloc" or "glibc"): jemalloc preloaded (LD_PRELOAD), asking for transparent huge pages
    (MALLOC_CONF thp:always, as _launch.huge_pages does for glibc's; a MALLOC_CONF of the user's is
    kept instead), unless the environment already preloads something (then nothing changes; with
    "jemalloc" too). A worker runs task after task, each building its tiles' arrays afresh and
    freeing them: glibc hands blocks over 32 MiB back to the kernel at once (its largest mmap
    threshold), and the next task has every page faulted in and zeroed again, where jemalloc
    keeps freed pages for a while and reuses them.
    "auto": jemalloc where Debian's libjemalloc2 is installed, else glibc's malloc."""
    from toposimp import UsageError

    if which == "glibc":
        return {}
    if which not in ("auto", "jemalloc"):
        raise ValueError(f"worker_malloc must be 'auto', 'jemalloc' or 'glibc', not {which!r}")
    import ctypes.util

    library = ctypes.util.find_library("jemalloc")
    if library is None:
        if which == "jemalloc":
            raise UsageError("--worker-malloc jemalloc: libjemalloc is not installed (Debian: apt install libjemalloc2)")
        return {}
    if environ.get("LD_PRELOAD"):
        return {}  # (the user's: kept)
    return {"LD_PRELOAD": library, "MALLOC_CONF": environ.get("MALLOC_CONF") or "thp:always"}


def local_worker_environment(worker_malloc, environ):
    """The environment the workers of a LocalCluster started here get (`environ`: this process's):
    glibc asking for transparent huge pages (_launch.huge_pages) and the allocator `worker_malloc`
    asks for (_worker_malloc). scripts/bench/ starts its clusters the same way."""
    return {"GLIBC_TUNABLES": _launch.huge_pages(environ.get("GLIBC_TUNABLES", "")), **_worker_malloc(worker_malloc, environ)}


def local_worker_config(environ):
    """The Dask settings a LocalCluster started here gives its workers (its nannies hand them this
    process's settings, not the environment's): Dask's statistical profiler off, unless `environ`
    sets it. That profiler looks at every thread's stack 100 times a second for the dashboard's
    profile page, which such a cluster does not serve (it starts without a dashboard): GSHHG at
    10 % on 2 workers, the first round's tasks took 3.42-3.69 s of the workers' time without it
    against 3.62-4.15 s with it (4 runs each)."""
    if "DASK_DISTRIBUTED__WORKER__PROFILE__ENABLED" in environ:
        return {}
    return {"distributed.worker.profile.enabled": False}


def _profiled_here():
    """Whether Dask's statistical profiler runs in this worker: "on" or "off"."""
    import dask.config
    return "on" if dask.config.get("distributed.worker.profile.enabled") else "off"


def _malloc_here():
    """The allocator of this process, as its mapped libraries say: "jemalloc" or "glibc"."""
    try:
        with open("/proc/self/maps") as maps:
            return "jemalloc" if "libjemalloc" in maps.read() else "glibc"
    except OSError:
        return "unknown"


class _Connecting:
    """distributed imported and, given a scheduler's address, a Client made, on a thread of its
    own while the engine reads the input and sets up without the GIL (the 0.4 s they take then
    overlap the engine's work: 0.1 s less a run on GSHHG, whose set-up keeps both cores busy);
    take() waits for them. close() never waits: a run that stops first (bad input, Ctrl-C) must not
    wait for an unreachable scheduler's connect timeout; a Client made after that is closed by the
    thread that made it."""

    def __init__(self, scheduler):
        import threading

        self.scheduler, self.client, self.error, self.abandoned = scheduler, None, None, False
        self.lock = threading.Lock()
        self.thread = threading.Thread(target=self._run, name="toposimp.dask connect", daemon=True)
        self.thread.start()

    def _run(self):
        client = None
        try:
            import distributed
            if self.scheduler:
                client = distributed.Client(self.scheduler)
        except Exception as error:  # (raised again by take(), where it is reported)
            self.error = error
        with self.lock:
            if not self.abandoned:
                self.client, client = client, None
        if client is not None:
            client.close()

    def take(self):
        """The Client (the caller closes it), once made; raises what stopped it."""
        from toposimp import UsageError

        self.thread.join()
        if isinstance(self.error, (OSError, ValueError)):  # (unreachable: OSError after Dask's connect timeout)
            raise UsageError(f"cannot reach the Dask scheduler at {self.scheduler}: {self.error}") from None
        if self.error is not None:
            raise self.error
        with self.lock:
            client, self.client = self.client, None
        return client

    def close(self):
        """The Client closed, if it was made and not taken; one still being made, once it is."""
        with self.lock:
            self.abandoned = True
            client, self.client = self.client, None
        if client is not None:
            client.close()


# What a worker holds besides its tiles (Python, Dask, numpy, this package: 115 MiB measured), and
# per vertex or control point of a tile at its peak (the tile's arrays as they come, the engine's,
# its grid, the outcome: 220 bytes measured on GSHHG's tiles; taken with room to spare).
WORKER_BASE = 128 * 2**20
BYTES_PER_POINT = 320


def fitting_tile_points(client, wanted, timeout=120):
    """The tile size (vertices and control points) to use on `client`'s workers: `wanted`, or less
    where the workers' memory limit (Dask's memory_limit) would not hold their tasks' tiles in half
    of it: as many tasks at once as the worker has Dask threads (`dask worker` starts with a thread
    a core by default), each with a tile at most. (A worker over 80 % of its limit stops taking
    tasks, and memory the engine frees stays counted until it is given back: a tile too big for a
    worker would stall the run.)"""
    from toposimp import UsageError

    try:
        client.wait_for_workers(1, timeout=timeout)
    except Exception as error:  # (distributed raises TimeoutError, or OSError when the scheduler is gone)
        raise UsageError(f"no Dask worker joined the scheduler within {timeout} s ({error})") from None
    limited = [(worker["memory_limit"], max(1, int(worker.get("nthreads") or 1)))
               for worker in client.scheduler_info()["workers"].values() if (worker.get("memory_limit") or 0) > 0]
    if not limited:
        return wanted
    limit, threads = min(limited, key=lambda w: (0.5 * w[0] - WORKER_BASE) / w[1])
    fits = int((0.5 * limit - WORKER_BASE) / threads // BYTES_PER_POINT)
    if fits < 10_000:
        each = "a task" if threads == 1 else f"{threads} tasks at once (its Dask threads)"
        raise UsageError(f"a Dask worker's memory limit ({limit / 2**20:.0f} MiB) leaves no room for the tiles of {each}: "
                         f"give each worker at least {(2 * (WORKER_BASE + threads * 10_000 * BYTES_PER_POINT)) / 2**20:.0f} MiB"
                         + (" or fewer threads (dask worker --nthreads)" if threads > 1 else ""))
    return min(wanted, fits)


# What the first round on the workers holds there per vertex of the map, over all workers, between
# its stages (every tile's pieces, states, keys and flags, and a stage's copy of a batch: 31 to 54
# bytes measured on the 45 M-vertex map and on GSHHG; taken with room to spare).
FIRST_ROUND_BYTES_PER_VERTEX = 64


# What `toposimp map` holds at its peak per byte of its input on disk: 4.7 on GSHHG (743 MiB for
# 158 MiB of .shp), 2.0 and 2.5 on the generated maps of 22 M and 201 M vertices as stored (their
# folders, with the control points' Shapefile).
WHOLE_MAP_BYTES_PER_INPUT_BYTE = 5


def _input_too_big(size, verbose=False):
    """Whether an input of `size` bytes on disk, read here whole, could take more than half the
    memory this process may still take (--first-round auto)."""
    room = _memory_here()
    needed = size * WHOLE_MAP_BYTES_PER_INPUT_BYTE
    big = room is not None and needed > 0.5 * room
    if verbose:
        sys.stderr.write(f"toposimp.dask: debug: the input, {size / 2**20:.0f} MiB on disk, could take about {needed / 2**20:.0f} MiB here "
                         "read whole, " + ("with no measure of the memory left here" if room is None else f"{room / 2**20:.0f} MiB left")
                         + (": its first round runs on the workers, which read it by parts (--first-round workers)\n" if big
                            else ": it is read here (--first-round here)\n"))
    return big


# What the command holds per live vertex once the first round's live map comes here (MapInParts):
# 91 bytes measured on GSHHG at 90 % (session 50: the command's peak 1 066 MiB, against 309 with
# the tiles kept on the workers, for 8.75 M live vertices), taken with a little room.
LIVE_BYTES_PER_VERTEX = 100


def _memory_here(root="/"):
    """The bytes this process may still take: the machine's available memory (MemAvailable), or
    less where a cgroup (v2, or v1's memory controller) limits this process; None where none of them
    can be read. (`root`: where /proc and /sys are, for the tests.)"""
    room = None
    try:
        with open(os.path.join(root, "proc/meminfo")) as meminfo:
            for line in meminfo:
                if line.startswith("MemAvailable:"):
                    room = int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    try:
        with open(os.path.join(root, "proc/self/cgroup")) as cgroup:
            lines = cgroup.read().splitlines()
    except OSError:
        lines = []
    for line in lines:
        number, controllers, path = (line.split(":", 2) + ["", ""])[:3]
        if number == "0" and controllers == "":
            folder, files = os.path.join(root, "sys/fs/cgroup" + path.rstrip("/")), ("memory.max", "memory.current")
        elif "memory" in controllers.split(","):
            folder, files = os.path.join(root, "sys/fs/cgroup/memory" + path.rstrip("/")), ("memory.limit_in_bytes", "memory.usage_in_bytes")
        else:
            continue
        try:
            with open(f"{folder}/{files[0]}") as limit_file:
                limit = limit_file.read().strip()
            if limit == "max" or int(limit) >= 2**60:  # (v1's "no limit" is a page short of 2^63)
                continue
            with open(f"{folder}/{files[1]}") as current_file:
                left = max(0, int(limit) - int(current_file.read()))
        except (OSError, ValueError):
            continue
        room = left if room is None else min(room, left)
    return room


def check_first_round_fits(client, vertices):
    """Raises UsageError unless the workers' memory limits (where set) hold the first round's tiles
    of a map of `vertices` in half of them, beside what each worker holds anyway: past 80 % of its
    limit a Dask worker stops taking tasks, and the run would stall."""
    from toposimp import UsageError

    limits = [worker.get("memory_limit") or 0 for worker in client.scheduler_info()["workers"].values()]
    if not limits or any(limit <= 0 for limit in limits):
        return
    room = sum(max(0, 0.5 * limit - WORKER_BASE) for limit in limits)
    needed = vertices * FIRST_ROUND_BYTES_PER_VERTEX
    if needed > room:
        raise UsageError(f"--first-round workers keeps the whole map's tiles on the workers (about {needed / 2**20:.0f} MiB for its "
                         f"{vertices} vertices); the {len(limits)} workers' memory limits leave room for {room / 2**20:.0f} MiB: "
                         f"add workers, raise their limits, or use --first-round here")


_INSTALL_HINT = "make this toposimp package importable on every worker (PYTHONPATH, or install it there)"


def check_workers(client):
    """Raises UsageError unless every worker of `client` runs tiles with this engine (the toposimp
    package importable there, of this version and tile format); returns each worker's cores (those
    its process may run on) by address."""
    from toposimp import UsageError

    def engine_there():  # (defined here so that Dask sends it by value: the worker may lack the package)
        import os

        try:
            from toposimp import _toposimp as engine
        except ImportError as error:
            return f"cannot import toposimp ({error})"
        cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count() or 1
        return [engine.version, getattr(engine, "parts_protocol", 0), cores]

    mine = [_toposimp.version, _toposimp.parts_protocol]
    cores = {}
    for address, answer in sorted(client.run(engine_there).items()):
        if not isinstance(answer, str) and answer[:2] == mine:
            cores[address] = answer[2]
            continue
        if isinstance(answer, str):
            why = answer
        else:
            why = f"it has toposimp {answer[0]} with tile format {answer[1]}, this is {mine[0]} with {mine[1]}"
        raise UsageError(f"the Dask worker {address} cannot run the tiles: {why}; {_INSTALL_HINT}")
    return cores


def task_threads_for(workers, cores):
    """The threads each task's engine may use: on every host, its cores shared among the Dask
    threads of its workers (at least 1 each; the least over the hosts). `workers`: the scheduler's
    worker records by address ("host", "nthreads"); `cores`: each worker's cores by address (those
    its process may run on; the largest on a host counts). A LocalCluster of one worker of one
    thread on 2 cores gives each task 2 threads; one of a worker a core, 1."""
    slots, host_cores = {}, {}
    for address, worker in workers.items():
        host = worker.get("host", address)
        slots[host] = slots.get(host, 0) + max(1, int(worker.get("nthreads") or 1))
        host_cores[host] = max(host_cores.get(host, 1), int(cores.get(address) or 1))
    if not slots:
        return 1
    return max(1, min(host_cores[host] // slots[host] for host in slots))


# A budget's selection gathers the (key, id) pairs of the bucket it falls in once that holds at
# most this many (12 bytes each), instead of a pass more over every tile.
PAIRS_GATHERED = 2_000_000


# The first round's tasks (src/python/parts.cpp: first_cut and the rest), each importing the
# engine where it runs.
def _first_cut(part, plan, options):
    from toposimp import _toposimp as engine
    return engine.first_cut(part, plan, plan["tile_level"], options)


def _item(value, k):
    return value[k]


def _first_pieces(cut, indices):
    """A part's pieces of a batch's tiles."""
    return [cut[1][i] for i in indices]


def _first_search(parts, options):
    """A batch of tiles, from their pieces (per part, in the parts' order) → (the tiles searched,
    their answers), by tile number."""
    from toposimp import _toposimp as engine
    pieces = {}
    for part in parts:
        for piece in part:
            pieces.setdefault(piece.number, []).append(piece)
    tiles, answers = [], []
    for number in sorted(pieces):
        tile, answer = engine.first_search(pieces[number], options)
        tiles.append(tile)
        answers.append(answer)
    return tiles, answers


def _first_queue(searched, border, marks, options):
    from toposimp import _toposimp as engine
    tiles, answers = [], []
    for tile in searched[0]:
        tile, answer = engine.first_queue(tile, border, marks, options)
        tiles.append(tile)
        answers.append(answer)
    return tiles, answers


def _first_histogram(queued, shift, high):
    from toposimp import _toposimp as engine
    return engine.first_histogram(queued[0], shift, high)


def _first_pairs_in(queued, shift, prefix):
    from toposimp import _toposimp as engine
    return engine.first_pairs_in(queued[0], shift, prefix)


def _first_ids_at(queued, key):
    from toposimp import _toposimp as engine
    return engine.first_ids_at(queued[0], key)


def _first_run(queued, groups, points, marks, bound, plan, options, live=True):
    """A batch's busy groups run (each a list of its tiles' places in the batch, with their control
    points), its other tiles' live vertices → (outcomes, live vertices); without `live`, the
    outcomes only (the tiles are kept: _kept_batch)."""
    from toposimp import _toposimp as engine
    tiles = queued[0]
    outcomes, lives, running = [], [], set()
    threads = options.get("threads", 1)
    if threads >= 2 and len(groups) >= threads:
        # (side by side, a thread each, as _run_groups' tasks run theirs; their control points all at once)
        answers = engine.first_runs([[tiles[i] for i in group] for group in groups], list(points), marks, bound, plan, options, live)
    else:
        answers = (engine.first_run([tiles[i] for i in group], inside, marks, bound, plan, options, live)
                   for group, inside in zip(groups, points))
    for group, (done, those) in zip(groups, answers):
        outcomes.extend(done)
        lives.extend(those)
        running.update(group)
    if live:
        lives.extend(engine.first_live(tile, marks, bound) for i, tile in enumerate(tiles) if i not in running and tile.vertices > 0)
    return outcomes, lives


# The rounds after the first from the first round's tiles kept on the workers (--kept-tiles;
# src/python/kept.cpp: kept_batch and the rest; map::KeptTiles here). Every task is pure: one
# that changes a batch makes a new one, so that Dask's lineage can build a lost one again.
KEPT_PER_WORKER = 4  # kept batches per worker (_kept_chunks)


def _kept_batch(marks, bound, *queued):
    from toposimp import _toposimp as engine
    return engine.kept_batch([tile for q in queued for tile in q[0]], marks, bound)


def _kept_chunks(who_has, keys, sizes):
    """The first round's batches (`keys`, their `sizes` in vertices) kept together by the worker
    that holds them (`who_has`: key → addresses), in up to KEPT_PER_WORKER chunks a worker, each of
    about a share of its vertices: [(address or None, [batch indices])], in a fixed order. Not one
    chunk a worker: a task that changes a kept batch makes a new one beside the old (_kept_advance),
    so a worker holds its largest chunk twice for a moment."""
    by_worker = {}
    for b, key in enumerate(keys):
        held = sorted(who_has.get(key, ()))
        by_worker.setdefault(held[0] if held else None, []).append(b)
    chunks = []
    for where, batches in sorted(by_worker.items(), key=lambda item: (item[0] is None, item[0] or "")):
        share = -(-sum(sizes[b] for b in batches) // KEPT_PER_WORKER)
        current, size = [], 0
        for b in batches:
            if current and size + sizes[b] > share:
                chunks.append((where, current))
                current, size = [], 0
            current.append(b)
            size += sizes[b]
        chunks.append((where, current))
    return chunks


def _kept_advance(batch, news, ran, plan, marks, options, *own):
    """(`own`: after the tiles' levels, the outcome lists of the groups that ran where this batch's
    tiles are: their states and waits are not sent through this process again.)"""
    from toposimp import _toposimp as engine
    return engine.kept_advance(batch, news, ran, plan, marks, options, [outcomes[0] if type(outcomes) is tuple else outcomes
                                                                        for outcomes in own])


def _kept_begin(batch, settled, marks, bound):
    """(A new batch, marked and settled for the round; its tiles' facts.)"""
    from toposimp import _toposimp as engine
    return engine.kept_begin_round(batch, settled, marks, bound)


def _kept_call(batch, name, *arguments):
    from toposimp import _toposimp as engine
    return getattr(engine, name)(batch, *arguments)


def _items(k, *values):
    return [value[k] for value in values]


def _kept_many(calls, *batches):
    """Per batch, engine.name(batch, *arguments) for each (name, arguments) of `calls`."""
    from toposimp import _toposimp as engine
    return [[getattr(engine, name)(batch, *arguments) for name, arguments in calls] for batch in batches]


def _kept_direct(keys_at, calls, dask_worker=None):
    """_kept_many's answers for the batches `keys_at[this worker's address]` (their keys), read
    from this worker's store, run by Client.run: one message each way, no task. None where one of
    them is not here (lost with a worker, or made elsewhere): then a task asks (_KeptStore._many)."""
    keys = keys_at.get(dask_worker.address)
    if keys is None:
        return None
    batches = []
    for key in keys:
        if key not in dask_worker.data:
            return None
        batches.append(dask_worker.data[key])
    return _kept_many(calls, *batches)


def _kept_run(batch, groups, points, marks, bound, plan, options):
    """A batch's groups (tile numbers) run, each with its tiles' control points → the outcomes,
    group after group."""
    from toposimp import _toposimp as engine
    outcomes = []
    for group, inside in zip(groups, points):
        outcomes.extend(engine.run_tile_group(engine.kept_inputs(batch, list(group), marks, bound, inside), plan, options))
    return outcomes


def _kept_run_gathered(inputs, plan, options):
    """A group whose tiles lie in several batches: their inputs (lists, in the group's order) run."""
    from toposimp import _toposimp as engine
    return engine.run_tile_group([tile for part in inputs for tile in part], plan, options)


class _KeptStore:
    """map::KeptTiles's questions to the first round's tiles, kept on the workers in batches (a few
    per worker: _kept_chunks): a question that changes nothing a task per worker, one that makes new
    batches a task per batch (src/python/kept.cpp: PythonStore)."""

    def __init__(self, tasks, client, batches, homes, numbers, plan, options, marks, own):
        self.tasks, self.client, self.batches = tasks, client, batches
        self.homes = homes  # per batch: the worker it was made on (None: any), where its tasks go
        self.own = own  # per batch: the futures of the outcome lists of the groups run where its tiles are
        self.where = {int(number): b for b, held in enumerate(numbers) for number in held}
        self.plan, self.options, self.marks = plan, options, marks
        self.round = 1
        self._ahead = {}  # answers asked for ahead (queued)
        self.direct = True  # questions asked straight of the workers (_many)

    def _gather(self, futures, what, release=True):
        import asyncio
        import concurrent.futures

        from toposimp import UsageError

        results = self.tasks._gather(self.client, futures, what, release=release)
        for result in results:
            # (A task cancelled: its data lost with a worker. distributed's own kind of it, where
            # it has one, derives from concurrent.futures'.)
            if isinstance(result, (concurrent.futures.CancelledError, asyncio.CancelledError)):
                # (Dask keeps how every kept batch was made while the batch made from it is wanted,
                # and builds a lost one again from the input up, round by round: a cancelled task
                # means that Dask itself gave up, e.g. a scheduler restarted under the run.)
                raise UsageError("a Dask worker holding kept tiles was lost and Dask cancelled the tasks that would build them again "
                                 "(run again, or without --kept-tiles)")
            if isinstance(result, BaseException):
                raise result
        return results

    def _at(self, b):
        """Where batch b's tasks go: its worker, or any other when that one is gone."""
        return {"workers": [self.homes[b]], "allow_other_workers": True} if self.homes[b] else {}

    def _each(self, name, *arguments, what="the kept tiles"):
        """engine.name(batch, *arguments) for every batch, in order (_many)."""
        return [answers[0] for answers in self._many([(name, arguments)], what)]

    def _many(self, calls, what):
        """Per batch, in order, engine.name(batch, *arguments) for each (name, arguments) of
        `calls`: questions that change nothing. These come in waves, one after another (hundreds
        in a round's levels above the tiles), and a Dask task costs about 11 ms a wave here where a
        Client.run costs 2-3: asked straight of the workers holding the batches (_kept_direct,
        `direct`), and of a task per worker (over the batches made there) only for those a worker
        does not hold (one lost: Dask builds them again from their lineage). The same answers."""
        from distributed import wait

        by_home = {}
        for b, home in enumerate(self.homes):
            by_home.setdefault(home, []).append(b)
        results = [None] * len(self.batches)
        left = list(by_home.items())
        # (Only while every home is a worker the scheduler lists, and until a Client.run fails:
        # from a loss on, the tasks ask, and Dask builds the lost batches again for them.)
        alive = self.client.scheduler_info()["workers"]
        if self.direct and all(home in alive for home in by_home):
            try:
                wait(self.batches)
                keys_at = {home: [self.batches[b].key for b in held] for home, held in by_home.items()}
                answers = self.tasks._run_direct(self.client, _kept_direct, keys_at, calls, what=what, workers=list(keys_at))
            except Exception:  # (a worker gone, say: the tasks below ask again, and fail as the question would)
                answers = {}
                self.direct = False
            left = []
            self.tasks.waves["straight"] += 1
            for home, held in by_home.items():
                mine = answers.get(home)
                if mine is None:
                    left.append((home, held))
                    continue
                for b, answer in zip(held, mine):
                    results[b] = answer
        if left:
            self.tasks.waves["through tasks"] += 1
            tasks = [_submit(self.client, _kept_many, calls, *[self.batches[b] for b in held], **self._at(held[0])) for _, held in left]
            for (_, held), answers in zip(left, self._gather(tasks, what)):
                for b, answer in zip(held, answers):
                    results[b] = answer
        return results

    def _by_home(self, task, futures, what):
        """task(*futures of one worker's batches) → its list of results, one per batch; all the
        results in the batches' order."""
        by_home = {}
        for b, home in enumerate(self.homes):
            by_home.setdefault(home, []).append(b)
        order = list(by_home.values())
        results = [None] * len(futures)
        for held, answers in zip(order, self._gather([task(*[futures[b] for b in held], **self._at(held[0])) for held in order], what)):
            for b, answer in zip(held, answers):
                results[b] = answer
        return results

    def advance(self, news, ran):
        import warnings

        import numpy

        news_after_tiles = bool(news["after_tiles"])
        self._ahead = {}
        # (Sent once, as a task's result rather than scattered, so that Dask can build a lost batch
        # again from its lineage: scattered data has none.)
        with warnings.catch_warnings():
            warnings.filterwarnings("ignore", message="Large object of size", category=UserWarning)
            news = _submit(self.client, _given, news)
        own = self.own if news_after_tiles else [[] for _ in self.batches]
        done = [_submit(self.client, _kept_advance, b, news, ran, self.plan, self.marks, self.options, *mine, **self._at(k))
                for k, (b, mine) in enumerate(zip(self.batches, own))]
        if news_after_tiles:
            self.own = [[] for _ in self.batches]
        self.batches = [_submit(self.client, _item, d, 0, **self._at(k)) for k, d in enumerate(done)]
        answers = self._by_home(lambda *made, **at: _submit(self.client, _items, 1, *made, **at), done,
                                "telling the kept tiles what the round changed")
        across = [a["across"] for a in answers if len(a["across"])]
        return {"across": numpy.concatenate(across) if across else numpy.zeros((0, 2), dtype=numpy.uint32),
                "moved": sum(a["moved"] for a in answers), "joined": sum(a["joined"] for a in answers)}

    def queued(self):
        # (With the count come the budget's first histogram, whose counts add up to it, and the
        # rings' locations at the tiles' borders: KeptTiles::next_round asks for the three in a
        # row, with no change to the tiles between. One wave instead of three.)
        answers = self._many([("kept_histogram", (48, 0)), ("kept_crossings", ())], "the kept tiles")
        self._ahead = {"histogram": [a[0] for a in answers], "crossings": [a[1] for a in answers]}
        return sum(int(a[0]["counts"].sum()) for a in answers)

    def select(self, wanted):
        import numpy

        def dense(histograms):
            total = numpy.zeros(1 << 16, dtype=numpy.uint64)
            for histogram in histograms:
                numpy.add.at(total, histogram["digits"], histogram["counts"])
            return total

        what = "selecting the round's budget"
        selector = _toposimp.DigitSelector(wanted)
        ahead = self._ahead.pop("histogram", None)
        total = dense(ahead if ahead is not None else self._each("kept_histogram", 48, 0, what=what))
        selector.counted(total)
        while selector.counting and int(total[selector.high & 0xffff]) > PAIRS_GATHERED:
            total = dense(self._each("kept_histogram", selector.shift, selector.high, what=what))
            selector.counted(total)
        if selector.counting:
            pairs = self._each("kept_pairs_in", selector.shift + 16, selector.high, what=what)
            return selector.choose_among(numpy.concatenate([p["keys"] for p in pairs]), numpy.concatenate([p["ids"] for p in pairs]))
        return selector.choose(numpy.concatenate(self._each("kept_ids_at", selector.key, what=what)))

    def crossings(self):
        ahead = self._ahead.pop("crossings", None)
        return [ring for rings in (ahead if ahead is not None else self._each("kept_crossings")) for ring in rings]

    def begin_round(self, settled, marks, bound):
        self.round += 1
        self._ahead = {}
        begun = [_submit(self.client, _kept_begin, b, settled, marks, bound, **self._at(k)) for k, b in enumerate(self.batches)]
        self.batches = [_submit(self.client, _item, d, 0, **self._at(k)) for k, d in enumerate(begun)]
        return [fact for facts in self._by_home(lambda *made, **at: _submit(self.client, _items, 1, *made, **at), begun, "starting the round")
                for fact in facts]

    def run(self, groups, points, marks, bound):
        # A group whose tiles are all in one batch runs where that batch is, with the batch's other
        # such groups; one spread over batches gathers its tiles' inputs into a task of its own.
        at = 0
        mine = [[] for _ in self.batches]
        spread = []
        for k, group in enumerate(groups):
            inside = points[at:at + len(group)]
            at += len(group)
            held = {self.where[int(number)] for number in group}
            if len(held) == 1:
                mine[held.pop()].append((k, group, inside))
            else:
                spread.append((k, group, inside))
        tasks, order = [], []
        for b, runs in enumerate(mine):
            if runs:
                tasks.append(_submit(self.client, _kept_run, self.batches[b], [g for _, g, _ in runs], [p for _, _, p in runs], marks, bound,
                                     self.plan, self.options, **self._at(b)))
                order.append([k for k, _, _ in runs])
                self.own[b].append(tasks[-1])
        for k, group, inside in spread:
            parts = []
            for number, one in zip(group, inside):
                parts.append(_submit(self.client, _kept_call, self.batches[self.where[int(number)]], "kept_inputs", [int(number)], marks, bound, [one]))
            tasks.append(_submit(self.client, _kept_run_gathered, parts, self.plan, self.options))
            order.append([k])
            for b in {self.where[int(number)] for number in group}:
                self.own[b].append(tasks[-1])
        results = self._gather(tasks, f"round {self.round}, tiles of level {self.plan.get('tile_level', 0)}", release=False)
        by_group = {}
        for ks, outcomes in zip(order, results):
            for k in ks:
                count = len(groups[k])
                by_group[k], outcomes = outcomes[:count], outcomes[count:]
        return [outcome for k in range(len(groups)) for outcome in by_group[k]]

    def input(self, number, marks, bound, points):
        [tiles] = self._gather([_submit(self.client, _kept_call, self.batches[self.where[int(number)]], "kept_inputs", [int(number)], marks,
                                        bound, [points])], "a kept tile")
        return tiles[0]

    def waits(self):
        import numpy

        waits = [w for w in self._each("kept_waits") if len(w)]
        return numpy.concatenate(waits) if waits else numpy.zeros((0, 2), dtype=numpy.uint32)

    def answer(self, ask):
        import numpy

        answers = self._each("kept_answer", ask, self.plan, what="gathering the levels above the tiles")
        merged = {key: numpy.concatenate([a[key] for a in answers]) for key in ("ids", "chain", "prev", "next", "points", "state", "marked",
                                                                               "flags", "in_boxes")}
        merged["outside"] = [piece for a in answers for piece in a["outside"]]
        return merged

    def tiles(self):
        return sum(self._gather([_submit(self.client, _kept_tiles, b) for b in self.batches], "the kept tiles"))


def _kept_tiles(batch):
    return batch.tiles


def _kept_numbers(batch):
    return batch.numbers


class _Tasks:
    """run_groups for the engine (src/python/parts.hpp): each round's tile groups as tasks on the
    client `connected()` gives, their outcomes back in order; and the first round built on the
    workers (first_round), unless `first_here`."""

    def __init__(self, connected, task_threads, progress=None, on_progress=None, first_here=True, top_runs=0, kept=False, verbose=False,
                 by_parts_only=False):
        self.connected, self.task_threads = connected, task_threads  # (None: task_threads_for the workers)
        self.threads = task_threads or 1
        self.waves = {"straight": 0, "through tasks": 0}  # the kept tiles' waves of questions (_KeptStore._many)
        self.kept, self.verbose = kept, verbose  # (kept: True, False or "auto": _keep_tiles)
        self.progress, self.on_progress = progress, on_progress
        if top_runs > 0:
            self.top_runs = top_runs  # (read by the engine: run_in_parts)
        self.checked = []  # the clients whose workers were checked
        if not first_here:
            self.first_round = self._first_round
            if by_parts_only:  # (read by the engine: on the workers only an input read by parts there)
                self.first_round_by_parts_only = True

    def _client(self):
        client = self.connected()
        if not any(c is client for c in self.checked):
            cores = check_workers(client)
            self.checked.append(client)
            if self.task_threads is None:
                self.threads = task_threads_for(client.scheduler_info()["workers"], cores)
                if self.verbose:
                    sys.stderr.write(f"toposimp.dask: debug: {self.threads} thread(s) a task (--task-threads: the workers' "
                                     f"cores {sorted(set(cores.values()))} shared among their Dask threads)\n")
        return client

    def __call__(self, groups, plan, options, round_number):
        import warnings

        # (Where the workers are not on this machine, a task's tiles travel with it through the
        # scheduler by design: each is used once, and the command may not reach the workers
        # itself. Dask's advice to scatter them first must not reach the user's terminal.)
        with warnings.catch_warnings(), _tiles_uncompressed():
            warnings.filterwarnings("ignore", message="Large object of size", category=UserWarning)
            return self._run_round(groups, plan, options, round_number)

    def _stage(self, what, done, total):
        if self.progress is not None:
            self.progress.stage(what, done, total)

    def _run_direct(self, client, function, *arguments, what, workers):
        """client.run(function, *arguments) on `workers`: their answers by address."""
        self._stage(what, 0, 1)
        answers = client.run(function, *arguments, workers=workers)
        self._stage(what, 1, 1)
        return answers

    def _gather(self, client, futures, what, on_progress=None, each=None, release=True):
        """The futures' results in order, with progress; or, with `each`, each(result) as they come,
        none kept. Each future is released once its result came, unless not `release`."""
        from distributed import as_completed
        from toposimp import UsageError

        results = [None] * len(futures)
        place = {future.key: k for k, future in enumerate(futures)}
        self._stage(what, 0, len(futures))
        try:
            for done, (future, result) in enumerate(as_completed(futures, with_results=True), 1):
                if each is None:
                    results[place[future.key]] = result
                else:
                    each(result)
                if release:
                    future.release()
                self._stage(what, done, len(futures))
                if on_progress is not None:
                    on_progress(done, len(futures))
        except ImportError as error:  # (a worker that joined after the check, without the package)
            raise UsageError(f"a Dask worker cannot run the tiles: {error}; {_INSTALL_HINT}") from None
        return results

    def _first_round(self, steps, plan, options):
        import warnings

        with warnings.catch_warnings():
            warnings.filterwarnings("ignore", message="Large object of size", category=UserWarning)
            return self._first(steps, plan, options)

    def _first(self, steps, plan, options):
        """The first round: the map's parts cut into tiles on the workers; the tiles, in batches of
        whole groups, searched for crossings, queued, their budget selected by reductions, their
        groups run; the live vertices back to `steps` (FirstSteps), which goes on here."""
        import numpy

        if self.progress is not None:
            self.progress.round, self.progress.tile_level = 1, plan.get("tile_level", 0)
        client = self._client()
        options = dict(options, threads=self.threads)
        workers = max(1, len(client.scheduler_info()["workers"]))
        check_first_round_fits(client, sum(steps.part_vertices(k) for k in range(len(steps))))

        def submit(*arguments, **keywords):
            return _submit(client, *arguments, **keywords)

        # Cut: each part's facts here, its tiles' pieces stay on the workers (a part of an input
        # read by parts is read there too).
        cuts, by_parts, part = [], False, None
        for k in range(len(steps)):
            part = steps.part(k)
            by_parts = by_parts or "shp" in part or "polygons_file" in part or "lines_file" in part
            cuts.append(submit(_first_cut, part, plan, options))
        del part
        facts = self._gather(client, [submit(_item, cut, 0) for cut in cuts],
                             "reading the input by parts and cutting it into tiles" if by_parts else "cutting the map into tiles")
        sizes, opens, where = {}, {}, {}  # per tile: its vertices, its open rings, its (part, place) pieces
        for k, part in enumerate(facts):
            steps.add_facts(part)
            for i, (number, count, open_rings) in enumerate(zip(part["tiles"].tolist(), part["tile_vertices"].tolist(), part["tile_open"])):
                sizes[number] = sizes.get(number, 0) + count
                opens.setdefault(number, []).append(open_rings)
                where.setdefault(number, []).append((k, i))
        # Batches of whole groups (tiles sharing a ring their cut ends do not settle), the biggest
        # first, as the rounds' tasks are cut (_batches); the tiles without vertices of their own
        # (segments passing through) go along to be searched.
        holding = [number for number in sorted(sizes) if sizes[number] > 0]
        everyone = steps.groups([(number, True, numpy.concatenate(opens[number])) for number in holding])
        batches = [[number for g in batch for number in everyone[g]]
                   for batch in _batches([sum(sizes[number] for number in group) for group in everyone], workers)]
        if not batches:
            batches = [[]]
        for j, number in enumerate(number for number in sorted(sizes) if sizes[number] == 0):
            batches[j % len(batches)].append(number)
        batches = [sorted(batch) for batch in batches]
        del facts, opens
        # Search: each batch's tiles from their pieces; the segments leaving tiles or-ed here.
        searched = []
        for batch in batches:
            parts = {}
            for number in batch:
                for k, i in where[number]:
                    parts.setdefault(k, []).append(i)
            searched.append(submit(_first_search, [submit(_first_pieces, cuts[k], parts[k]) for k in sorted(parts)], options))
        del cuts, where
        for answers in self._gather(client, [submit(_item, s, 1) for s in searched], "searching the tiles for crossings"):
            for answer in answers:
                steps.found(answer)
        border = steps.border()
        marks = steps.marks
        queued = [submit(_first_queue, s, border, marks, options) for s in searched]
        del searched
        answers = self._gather(client, [submit(_item, q, 1) for q in queued], "queueing the tiles' vertices")
        for batch in answers:
            for answer in batch:
                steps.queued(answer["pinned"], answer["queued"])
        # The budget: the wanted-th smallest (key, id) over all tiles, a 16-bit digit of the keys a
        # pass (the first pass came with the answers above), until the bucket it falls in is small
        # enough to be gathered here.
        wanted = steps.wanted()
        marks = steps.marks  # (off now for a count target that runs as --max)

        def dense(histograms):
            total = numpy.zeros(1 << 16, dtype=numpy.uint64)
            for histogram in histograms:
                numpy.add.at(total, histogram["digits"], histogram["counts"])
            return total

        if wanted > 0:
            selector = _toposimp.DigitSelector(wanted)
            total = dense(answer["histogram"] for batch in answers for answer in batch)
            selector.counted(total)
            while selector.counting and int(total[selector.high & 0xffff]) > PAIRS_GATHERED:
                total = dense(self._gather(client, [submit(_first_histogram, q, selector.shift, selector.high) for q in queued],
                                           "selecting the round's budget"))
                selector.counted(total)
            if selector.counting:
                pairs = self._gather(client, [submit(_first_pairs_in, q, selector.shift + 16, selector.high) for q in queued],
                                     "selecting the round's budget")
                bound = selector.choose_among(numpy.concatenate([p["keys"] for p in pairs]), numpy.concatenate([p["ids"] for p in pairs]))
            else:
                ids = self._gather(client, [submit(_first_ids_at, q, selector.key) for q in queued], "selecting the round's budget")
                bound = selector.choose(numpy.concatenate(ids))
            steps.bound(*bound)
        groups = []
        if wanted > 0 or not marks:
            groups = steps.groups([(a["number"], marks and tuple(a["smallest"]) <= tuple(bound), a["open"])
                                   for batch in answers for a in batch if a["vertices"] > 0])
        del answers
        bound = steps.bound_now
        kept = self._keep_tiles(sum(sizes.values()))
        # Run: each batch's busy groups where its tiles are, and its other tiles' live vertices.
        place = {number: (b, i) for b, batch in enumerate(batches) for i, number in enumerate(batch)}
        busy = [[] for _ in batches]
        for group in groups:
            busy[place[group[0]][0]].append(group)
        runs = [submit(_first_run, q, [[place[number][1] for number in group] for group in mine],
                       [[steps.points(number) for number in group] for group in mine], marks, bound, plan, options, not kept)
                for q, mine in zip(queued, busy)]
        if kept:
            self._gather(client, runs, f"round 1, tiles of level {plan.get('tile_level', 0)}", self.on_progress,
                         each=lambda result: steps.add([], result[0]), release=False)
            # The tiles stay on the workers for the rounds after (_KeptStore), the batches on each
            # worker together in a few (_kept_chunks): every question of the rounds after is a
            # task per kept batch, and Dask's cost per task (about a millisecond) is paid per wave.
            chunks = _kept_chunks(client.who_has(queued), [q.key for q in queued], [sum(sizes[n] for n in batch) for batch in batches])
            batches = [submit(_kept_batch, marks, bound, *[queued[b] for b in chunk], **({"workers": [where_], "allow_other_workers": True}
                                                                                          if where_ else {}))
                       for where_, chunk in chunks]
            del queued
            own = [[runs[b] for b in chunk] for _, chunk in chunks]  # (the groups' outcomes stay there for the first news)
            numbers = self._gather(client, [submit(_kept_numbers, b) for b in batches], "keeping the tiles")
            steps.keep(_KeptStore(self, client, batches, [where_ for where_, _ in chunks], numbers, plan, options, marks, own))
            return
        del queued
        self._gather(client, runs, f"round 1, tiles of level {plan.get('tile_level', 0)}", self.on_progress,
                     each=lambda result: steps.add(result[1], result[0]))
        steps.finish()

    def _keep_tiles(self, vertices):
        """Whether the first round's tiles stay on the workers (self.kept; "auto": when the live map
        after the first round, at most the map's `vertices` (how many the round removes is known
        only once it ran), could take more than half the memory this process may still take)."""
        if self.kept != "auto":
            return self.kept
        room = _memory_here()
        needed = vertices * LIVE_BYTES_PER_VERTEX
        kept = room is not None and needed > 0.5 * room
        if self.verbose:
            sys.stderr.write(f"toposimp.dask: debug: the live map after the first round, at most {vertices} vertices, could take up to "
                             f"{needed / 2**20:.0f} MiB here, "
                             + ("with no measure of the memory left here" if room is None else f"{room / 2**20:.0f} MiB left")
                             + (": its tiles stay on the workers (--kept-tiles)\n" if kept else ": it comes here\n"))
        return kept

    def _run_round(self, groups, plan, options, round_number):
        from distributed import as_completed
        from toposimp import UsageError

        progress, on_progress = self.progress, self.on_progress
        if progress is not None:
            progress.round, progress.tile_level = round_number, plan.get("tile_level", 0)
        client = self._client()
        options = dict(options, threads=self.threads)
        workers = max(1, len(client.scheduler_info()["workers"]))
        batches = _batches([groups.points(k) for k in range(len(groups))], workers)
        total = len(batches)
        # A few tasks per worker in flight, not all: each holds its tiles on its worker until it
        # runs (all at once, 225 tasks of a 45 M-vertex map filled two 512 MiB workers, which
        # then stopped). groups[k] builds group k's tiles here when its task is sent, and they
        # are dropped here once sent.
        window = 4 * workers
        sender = _StraightSender(client) if _workers_here(client) else None
        # (A task lost with its worker more often than Dask lets a task kill one stops the run, as
        # Dask's KilledWorker would: a tile that kills every worker it runs on.)
        import dask.config
        allowed = dask.config.get("distributed.scheduler.allowed-failures", 3)
        losses = {}
        place = {}
        running = as_completed(with_results=True)
        following = iter(range(total))

        def submit(b):
            tiles = [groups[k] for k in batches[b]]
            if sender is None:
                future = _submit(client, _run_groups, (_given, tiles), plan=plan, options=options)
            else:
                future = sender.submit(tiles, plan, options)
            place[future.key] = b
            running.add(future)

        def submit_next():
            b = next(following, None)
            if b is not None:
                submit(b)

        for _ in range(window):
            submit_next()
        results = [None] * len(groups)
        if progress is not None:
            progress.tiles(0, total)
        done = 0
        try:
            for future, result in running:
                b = place.pop(future.key)
                if sender is not None and sender.lost(future):
                    losses[b] = losses.get(b, 0) + 1
                    if losses[b] > allowed:
                        raise UsageError(f"a task of round {round_number}'s tiles lost its Dask worker {losses[b]} times "
                                         f"(the workers die running it: their memory limit?)")
                    submit(b)  # (its worker died with its tiles: built and sent again)
                    continue
                for k, outcomes in zip(batches[b], result):
                    results[k] = outcomes
                future.release()
                done += 1
                submit_next()
                if progress is not None:
                    progress.tiles(done, total)
                if on_progress is not None:
                    on_progress(done, total)
        except ImportError as error:  # (a worker that joined after the check, without the package)
            raise UsageError(f"a Dask worker cannot run the tiles: {error}; {_INSTALL_HINT}") from None
        return results


def _workers_here(client):
    """Whether every worker of `client` listens on this machine (a loopback address, or one of this
    host's): then the command can reach them itself (_StraightSender)."""
    import ipaddress
    import socket
    from urllib.parse import urlsplit

    addresses = list(client.scheduler_info()["workers"])
    if not addresses:
        return False
    own = None
    for address in addresses:
        split = urlsplit(address)
        if split.scheme not in ("tcp", "tls") or not split.hostname:
            return False
        try:
            if ipaddress.ip_address(split.hostname).is_loopback:
                continue
        except ValueError:
            pass
        if own is None:
            own = {socket.gethostname()}
            try:
                own |= {info[4][0] for info in socket.getaddrinfo(socket.gethostname(), None)}
            except OSError:
                pass  # (the name alone, then)
        if split.hostname not in own:
            return False
    return True


class _StraightSender:
    """A round's tasks with their tiles sent by this process straight to the worker that runs them
    (Dask's scatter, direct), not through the scheduler, which would receive and pass on every byte
    (GSHHG's first round: 178 MB, 0.45 s of the scheduler's CPU on a machine whose cores the workers
    need). Each task goes to the worker with the fewest of them under way; a task whose worker died
    with its tiles (Dask cancels it: scattered data has no task to rebuild it from) is sent again by
    the caller (lost)."""

    # Attempts to send a task's tiles, each to a worker there was, before the run stops.
    ATTEMPTS = 10

    def __init__(self, client):
        self.client = client
        self.under_way = {}  # worker -> tasks sent to it and not yet done
        self.worker_of = {}  # task key -> worker

    def submit(self, tiles, plan, options):
        from toposimp import UsageError

        why = None
        for _ in range(self.ATTEMPTS):
            workers = sorted(self.client.scheduler_info()["workers"])
            if not workers:
                self.client.wait_for_workers(1)
                continue
            worker = min(workers, key=lambda w: (self.under_way.get(w, 0), w))
            try:
                [data] = self.client.scatter([tiles], workers=[worker], direct=True, hash=False)
            except OSError as error:  # (the worker went between the list and the send: another)
                why = error
                self.under_way.pop(worker, None)
                continue
            future = _submit(self.client, _run_groups, data, plan=plan, options=options,
                             workers=[worker], allow_other_workers=True)
            self.under_way[worker] = self.under_way.get(worker, 0) + 1
            self.worker_of[future.key] = worker
            return future
        raise UsageError(f"the Dask workers could not take a task's tiles ({why})")

    def lost(self, future):
        """Whether `future` (done) was cancelled with its worker; either way it is no longer under
        way there."""
        worker = self.worker_of.pop(future.key, None)
        if worker in self.under_way:
            self.under_way[worker] -= 1
        return future.status == "cancelled"


def _submit(client, function, *arguments, **keywords):
    """client.submit(function, ..., pure=False), without the client's note, for Dask's dashboard, of
    the source of the code that submits the task (inspect.getsource of the caller's function, unless
    its module is ignored: 5 ms a task here, 0.1 s of GSHHG's run on 2 workers; this code's source
    is of no use there)."""
    import dask.config

    with dask.config.set({"distributed.diagnostics.computations.ignore-modules": [".*"]}):
        return client.submit(function, *arguments, pure=False, **keywords)


def _tasks(connected, task_threads, progress=None, on_progress=None, first_here=True, top_runs=0, kept=False, verbose=False,
           by_parts_only=False):
    return _Tasks(connected, task_threads, progress, on_progress, first_here, top_runs, kept, verbose, by_parts_only)


class Tiles:
    """A distributed.Client and how to cut the work for it (the options of the same names above):
    toposimp.simplify(..., client=Tiles(client, tile_points=200_000)). A plain Client takes the
    defaults."""

    def __init__(self, client, *, tile_level=-1, tile_points=1_000_000, task_threads=None, local_budget=None, first_round="here"):
        self.client, self.tile_level, self.tile_points = client, tile_level, tile_points
        self.task_threads = task_threads
        self.local_budget = LOCAL_BUDGET if local_budget is None else local_budget
        if first_round not in ("workers", "here"):
            raise ValueError(f"first_round must be 'workers' or 'here', not {first_round!r}")
        self.first_here = first_round == "here"

    def _parts(self):
        return (_tasks(lambda: self.client, self.task_threads, first_here=self.first_here), self.tile_level,
                lambda: fitting_tile_points(self.client, self.tile_points), self.local_budget)


def _main_thread():
    import threading
    return threading.current_thread() is threading.main_thread()


def main(argv=None):
    argv = list(sys.argv[1:] if argv is None else argv)
    if not argv or argv[0] in ("-h", "--help"):
        sys.stdout.write(USAGE)
        return 0 if argv else 2
    if argv[0] != "map":
        sys.stderr.write(f"toposimp.dask: error: the command is 'map', not '{argv[0]}'\n" + USAGE)
        return 2
    if any(a in ("-h", "--help") for a in argv[1:]):
        sys.stdout.write(USAGE)
        return 0
    options, rest = _split_arguments(argv[1:])
    quiet = "-q" in rest or "--quiet" in rest

    ended_by = []

    def terminate(number, frame):
        ended_by.append(number)
        raise KeyboardInterrupt

    # Ctrl-C stops the engine (the module's own handler while it runs) or the wait for the tasks;
    # a kill, the same. The output being written is removed as the run unwinds.
    signal.signal(signal.SIGTERM, terminate)
    try:
        return run(rest, scheduler=options.scheduler, workers=options.workers, tile_level=options.tile_level,
                   tile_points=options.tile_points, task_threads=options.task_threads, local_budget=options.local_budget,
                   first_round=options.first_round, send_input=options.send_input,
                   worker_malloc=options.worker_malloc, top_runs=options.top_runs, kept_tiles=options.kept_tiles, quiet=quiet)
    except KeyboardInterrupt:
        sys.stderr.write("toposimp.dask: interrupted; no output written\n")
        return 128 + (ended_by[0] if ended_by else signal.SIGINT)
    except Exception as error:
        from toposimp import InputError, UsageError
        # (An input error met by a task: its part of the input, read on a worker.)
        if not isinstance(error, (UsageError, InputError)):
            raise
        sys.stderr.write(f"toposimp.dask: error: {error}; no output written\n")
        return 2


def _exit(status):
    """The command's end: the atexit handlers (Dask's, logging's), the standard streams flushed,
    then the process ends without Python tearing down its modules and threads' state one by one,
    which after a run, with distributed's modules loaded, takes 0.1-0.2 s and does nothing the
    system does not: the output is written and closed, and so are the Client and the
    LocalCluster, by then."""
    import atexit

    atexit._run_exitfuncs()
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.flush()
        except (OSError, ValueError):  # (a reader gone, or a stream closed)
            if status == 0:
                status = 1
    os._exit(status)


if __name__ == "__main__":
    _launch.restart_with_huge_pages()  # (run as a script: the package did it for -m)
    _exit(main())

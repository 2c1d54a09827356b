#!/usr/bin/python3
"""toposimp map in one process against python3 -m toposimp.dask map on 1, 2 and 4 Dask workers
(a LocalCluster started here, outside the timing), on the same input in the same run: wall time,
the command's peak memory, each worker's peak memory, and whether the output is byte-identical.

Each row's runs alternate with runs of the single process (single, dask, single, dask, ...), and
its ratio is the median of its own runs over the median of the single runs beside them: on a
shared machine whose speed drifts (the single process moved by 0.5 s between two bench runs in a
row), runs taken minutes apart would compare two machines. The first run on each new cluster is
timed apart ("first"): its workers still import the engine.

    scripts/bench/dask_bench.py BUILD_DIR [--input build/bench-data/gshhg.shp] [--runs 3]
                                [--workers 1,2,4] [--target "--keep 10%" --target "--max"]
                                [--variant "" --variant "--first-round here"]
                                [--worker-env GLIBC_TUNABLES=glibc.malloc.hugetlb=1 --worker-env ...]

BUILD_DIR holds the toposimp executable and python/ (the package). Each --variant (toposimp.dask
options; default: none) is a row of its own, on a LocalCluster of its own. The LocalCluster's workers
start with --worker-env's variables (default: what toposimp.dask gives the workers of the
LocalCluster it starts, local_worker_environment and local_worker_config: transparent huge pages
asked for, jemalloc preloaded where it is installed, as --worker-malloc auto does, and Dask's
profiler off; none of them with --worker-env ""). Prints a Markdown table.
"""
import argparse
import os
import pathlib
import shlex
import statistics
import subprocess
import sys
import tempfile
import time

# The environment as it was before Dask's LocalCluster ran here: its nannies write the variables
# they set for their workers (OMP_NUM_THREADS=1, MALLOC_TRIM_THRESHOLD_=65536, ...: Dask's
# distributed.nanny.pre-spawn-environ) into this process's environment too, where every command
# started later would inherit them (a toposimp on one thread, glibc returning memory on every
# free).
CLEAN_ENV = dict(os.environ)


def timed(command, env=None):
    """(seconds, peak RSS in MiB of the command itself) of a run that must succeed, in `env` (default:
    CLEAN_ENV)."""
    start = time.perf_counter()
    done = subprocess.run(["/usr/bin/time", "-f", "%M", *command], capture_output=True, text=True,
                          env=CLEAN_ENV if env is None else env)
    seconds = time.perf_counter() - start
    if done.returncode != 0:
        sys.exit(f"failed: {shlex.join(command)}\n{done.stderr}")
    peak_kb = int(done.stderr.strip().splitlines()[-1])
    return seconds, peak_kb / 1024


def worker_peaks(client):
    """Each worker's peak resident memory in MiB: VmHWM, its own address space's high-water mark.
    (Not getrusage's ru_maxrss: Linux carries that over the exec that starts a spawned worker, so
    a worker would report its parent's peak when that was higher.)"""
    def peak():
        with open("/proc/self/status") as status:
            for line in status:
                if line.startswith("VmHWM:"):
                    return int(line.split()[1])
        return 0
    return sorted(v / 1024 for v in client.run(peak).values())


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("build")
    parser.add_argument("--input", default="build/bench-data/gshhg.shp")
    parser.add_argument("--runs", type=int, default=3)
    parser.add_argument("--workers", default="1,2,4")
    parser.add_argument("--target", action="append")
    parser.add_argument("--threads", type=int, default=2, help="toposimp map -j (the single process)")
    parser.add_argument("--variant", action="append", help="toposimp.dask options of a row (repeat for several)")
    parser.add_argument("--worker-env", action="append", metavar="NAME=VALUE",
                        help="the workers' environment (default: as toposimp.dask's LocalCluster)")
    a = parser.parse_args()
    targets = a.target or ["--keep 10%", "--max"]
    build = pathlib.Path(a.build).resolve()
    env = dict(CLEAN_ENV, PYTHONPATH=str(build / "python"))
    sys.path.insert(0, str(build / "python"))
    from distributed import Client, LocalCluster
    from toposimp import dask as toposimp_dask

    import dask.config

    if a.worker_env:
        worker_env, worker_config = dict(v.split("=", 1) for v in a.worker_env if v), {}
    else:
        worker_env = toposimp_dask.local_worker_environment("auto", CLEAN_ENV)
        worker_config = toposimp_dask.local_worker_config(CLEAN_ENV)

    rows = []
    with tempfile.TemporaryDirectory() as folder:
        out = pathlib.Path(folder)
        for target in targets:
            reference = out / "single.shp"

            def single_run():
                return timed([str(build / "toposimp"), "map", a.input, "-o", str(reference), "-q", "--overwrite", "-j", str(a.threads),
                              *shlex.split(target)])

            single_run()  # (the input in the page cache, the reference written)
            for workers, variant in [(int(w), v) for w in a.workers.split(",") for v in (a.variant or [""])]:
                os.environ.update(worker_env)  # (read by the worker processes as they start)
                with dask.config.set(worker_config):
                    cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=None)
                client = Client(cluster)
                output = out / "dask.shp"
                command = [sys.executable, "-m", "toposimp.dask", "map", a.input, "-o", str(output), "-q", "--overwrite",
                           "--scheduler", cluster.scheduler_address, *shlex.split(target), *shlex.split(variant)]
                first, _ = timed(command, env=env)
                singles, runs = [], []
                identical = True
                for _ in range(a.runs):
                    singles.append(single_run())
                    runs.append(timed(command, env=env))
                    identical = identical and all((out / f"dask{ext}").read_bytes() == (out / f"single{ext}").read_bytes()
                                                  for ext in (".shp", ".shx", ".dbf"))
                peaks = worker_peaks(client)
                client.close()
                cluster.close()
                s = statistics.median(t for t, _ in singles)
                d = statistics.median(t for t, _ in runs)
                rows.append((target, f"toposimp.dask{' ' + variant if variant else ''}, {workers} worker{'s' if workers > 1 else ''}", d,
                             s, d / s, min(t for t, _ in runs) / s, max(t for t, _ in runs) / s, first, max(m for _, m in runs),
                             max(m for _, m in singles), " / ".join(f"{p:.0f}" for p in peaks), "yes" if identical else "NO"))
    print(f"input: {a.input}; medians of {a.runs} runs, each beside a run of toposimp map -j {a.threads}; LocalCluster started "
          f"before the timing, one thread per worker{', workers with ' + ' '.join(f'{k}={v}' for k, v in worker_env.items()) if worker_env else ''}"
          f"{', Dask settings ' + ' '.join(f'{k}={v}' for k, v in worker_config.items()) if worker_config else ''}")
    print()
    print("| target | run | seconds | single s (beside) | × single | runs × single | first run s | command peak MiB (single) "
          "| worker peaks MiB | output identical |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for target, run, seconds, single, ratio, low, high, first, peak, single_peak, workers, same in rows:
        print(f"| `{target}` | {run} | {seconds:.2f} | {single:.2f} | {ratio:.2f} | {low:.2f}–{high:.2f} | {first:.2f} | "
              f"{peak:.0f} ({single_peak:.0f}) | {workers} | {same} |")


if __name__ == "__main__":
    main()

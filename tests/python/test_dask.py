"""python3 -m toposimp.dask: the map engine's tiles as Dask tasks on a real scheduler and workers
(separate processes, TCP on 127.0.0.1), the output byte for byte toposimp map's, also when a
worker is killed in the middle."""
import json
import os
import pathlib
import re
import signal
import socket
import subprocess
import sys
import time

import pytest

distributed = pytest.importorskip("distributed", reason="python3-distributed is not installed (apt install python3-distributed)")

ROOT = pathlib.Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "scripts" / "bench"))
import generate_map  # noqa: E402

# GeoPackages stamp the time they are written; both runs are given the same.
SAME_DATE = ["--config", "OGR_CURRENT_DATE", "2000-01-01T00:00:00Z"]


@pytest.fixture(scope="module")
def cluster(tmp_path_factory):
    """A scheduler and three workers (no nanny: a killed worker stays dead, and the test that
    killed it starts another: cluster[1].append(start())), and a client."""
    folder = tmp_path_factory.mktemp("dask")
    address_file = folder / "scheduler.json"
    env = dict(os.environ)
    common = ["--no-dashboard"]
    processes = [subprocess.Popen([sys.executable, "-m", "distributed.cli.dask_scheduler", "--host", "127.0.0.1", "--port", "0",
                                   "--scheduler-file", str(address_file), *common],
                                  env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)]
    deadline = time.monotonic() + 60
    while not address_file.exists() and time.monotonic() < deadline:
        time.sleep(0.1)
    assert address_file.exists(), "the scheduler did not start"

    def start():
        worker = subprocess.Popen([sys.executable, "-m", "distributed.cli.dask_worker", "--scheduler-file", str(address_file),
                                   "--nthreads", "1", "--no-nanny", "--local-directory", str(folder / f"w{len(processes)}"), *common],
                                  env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        processes.append(worker)
        return worker

    workers = [start() for _ in range(3)]
    client = distributed.Client(scheduler_file=str(address_file))
    client.wait_for_workers(3, timeout=60)
    client.start_worker = start
    yield client, workers
    client.close()
    for process in processes:
        process.kill()
        process.wait()


@pytest.fixture(scope="module")
def generated(tmp_path_factory):
    folder = tmp_path_factory.mktemp("map")
    return generate_map.generate(folder, cells=24, edge_vertices=30, rivers=40, river_steps=400, roads=6, points=8000, seed=3)


@pytest.fixture(scope="module")
def generated_shapefiles(tmp_path_factory):
    """Rivers that cross each other and themselves as a plain PolyLine Shapefile, and places."""
    folder = tmp_path_factory.mktemp("shapefiles")
    generate_map.generate_shapefiles(folder, cells=24, edge_vertices=4, rivers=200, river_steps=400, roads=2, points=8000, seed=4)
    return folder / "rivers.shp", folder / "places.shp"


@pytest.fixture(scope="module")
def generated_cells(tmp_path_factory):
    """A coverage of 1 600 cells with wavy borders as a plain Polygon Shapefile, and places."""
    folder = tmp_path_factory.mktemp("cells")
    generate_map.generate_shapefiles(folder, cells=40, edge_vertices=40, rivers=0, river_steps=0, roads=0, points=8000, seed=5)
    return folder / "cells.shp", folder / "places.shp"


@pytest.mark.parametrize("first_round, input_kind",
                         [("here", "gpkg"), ("workers", "gpkg"), ("workers", "shapefile"), ("workers", "polygon shapefile")])
def test_killed_worker_changes_nothing(cluster, generated, generated_shapefiles, generated_cells, binary, tmp_path, capsys, monkeypatch,
                                       first_round, input_kind):
    """A worker killed while it runs tasks: the same bytes. With the first round on the workers,
    the tasks read their parts of the input themselves (those of the killed worker again, from
    their lineage): a GeoPackage's cells, rivers and roads, a Shapefile of lines, or one of a
    polygon coverage."""
    from toposimp import dask as toposimp_dask

    client, workers = cluster
    lines, places = {"gpkg": generated, "shapefile": generated_shapefiles, "polygon shapefile": generated_cells}[input_kind]
    suffix = ".gpkg" if input_kind == "gpkg" else ".shp"
    # Targets that rounds reach (crossing rivers and roads pin many vertices: a target no run can
    # reach runs as --max, in one round).
    keep = {"gpkg": "30%", "shapefile": "50%", "polygon shapefile": "10%"}[input_kind]
    arguments = [str(lines), "-p", str(places), "--keep", keep, *SAME_DATE]
    reference = tmp_path / ("reference" + suffix)
    done = subprocess.run([binary, "map", *arguments, "-o", str(reference)], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr

    pids = client.run(os.getpid)  # worker address → its process id
    killed = {}

    def try_kill():
        # A worker with tasks under way, so that they are lost with it and run again elsewhere
        # (with the first round on the workers, tasks of its last stage).
        for address, keys in client.processing().items():
            if first_round == "workers" and not any(str(key).startswith("_first_run") for key in keys):
                continue
            if keys and pids.get(address) in [w.pid for w in workers]:
                killed["address"], killed["tasks"], killed["keys"] = address, len(keys), [str(key) for key in keys]
                os.kill(pids[address], signal.SIGKILL)
                return

    def kill_one(done, total):
        if not killed and done >= 2 and first_round == "here":
            try_kill()

    if first_round == "workers":
        # (As soon as the first round's last stage is under way: its tasks are short.)
        gather = toposimp_dask._Tasks._gather

        def gather_killing(self, client_, futures, what, on_progress=None, each=None, release=True):
            deadline = time.monotonic() + 30
            while what.startswith("round 1") and not killed and time.monotonic() < deadline and not all(f.done() for f in futures):
                try_kill()
            return gather(self, client_, futures, what, on_progress, each, release)

        monkeypatch.setattr(toposimp_dask._Tasks, "_gather", gather_killing)

    # The workers listen here, so each round's tiles go to them straight (_StraightSender): the
    # killed worker's tasks are cancelled with their tiles, and sent again.
    sent, lost = [], []
    straight_submit, straight_lost = toposimp_dask._StraightSender.submit, toposimp_dask._StraightSender.lost

    def counted_submit(self, *arguments):
        sent.append(1)
        return straight_submit(self, *arguments)

    def counted_lost(self, future):
        answer = straight_lost(self, future)
        if answer:
            lost.append(future.key)
        return answer

    monkeypatch.setattr(toposimp_dask._StraightSender, "submit", counted_submit)
    monkeypatch.setattr(toposimp_dask._StraightSender, "lost", counted_lost)

    output = tmp_path / ("dask" + suffix)
    capsys.readouterr()
    status = toposimp_dask.run([*arguments, "-o", str(output), "-v"], client=client, tile_level=1, local_budget=0,
                               quiet=input_kind == "gpkg", on_progress=kill_one, first_round=first_round)
    assert status == 0
    assert killed, "no worker had tasks under way after the first results"
    assert killed["tasks"] > 0
    assert sent, "the rounds' tiles did not go to the workers straight"
    if first_round == "here":  # (killed in a round: its tasks sent again)
        assert lost, "no task was lost with the killed worker"
    if first_round == "workers":  # (killed in the first round: its tiles, held by the worker, are built again)
        assert any(key.startswith("_first_run") for key in killed["keys"]), killed["keys"]
    assert killed["address"] not in client.scheduler_info()["workers"]
    workers.append(client.start_worker())  # (three again for the tests after)
    client.wait_for_workers(3, timeout=60)
    err = capsys.readouterr().err
    assert ("vertices (left in the file)" in err) == (first_round == "workers")
    assert "the input is read here, whole" not in err
    if first_round == "workers" and input_kind != "gpkg":  # (the GeoPackage's runs are quiet: no progress lines)
        assert "reading the input by parts and cutting it into tiles:" in err
    for extension in (".gpkg",) if input_kind == "gpkg" else (".shp", ".shx", ".dbf"):
        assert output.with_suffix(extension).read_bytes() == reference.with_suffix(extension).read_bytes(), extension


@pytest.mark.parametrize("layers, suffix", [(["cells", "rivers", "roads"], "gpkg"), (["rivers"], "geojson"), (["cells"], "geojson"),
                                            (["cells", "rivers", "roads"], "topojson")])
def test_a_folder_of_layers_read_by_parts_on_the_workers(cluster, generated_shapefiles, binary, tmp_path, capsys, layers, suffix):
    """Cells, rivers and roads of a folder of Shapefiles to a GeoPackage, and the rivers (lines)
    or the cells (a polygon coverage) alone to a GeoJSON (toposimp's own writer, each feature's
    vertices read again from its file), and all three to a TopoJSON (its arcs read again from the
    files: a coverage's from the rings that make them), read by parts on real workers: the same
    bytes as toposimp map."""
    from toposimp import dask as toposimp_dask

    client, _ = cluster
    rivers, places = generated_shapefiles
    arguments = [str(rivers.parent), *(a for layer in layers for a in ("-l", layer)), "-p", str(places), "--keep", "10%", *SAME_DATE]
    reference = tmp_path / f"reference.{suffix}"
    done = subprocess.run([binary, "map", *arguments, "-o", str(reference)], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    output = tmp_path / f"dask.{suffix}"
    capsys.readouterr()
    status = toposimp_dask.run([*arguments, "-o", str(output), "-v"], client=client, tile_level=1, local_budget=0, first_round="workers")
    err = capsys.readouterr().err
    assert status == 0, err
    assert "vertices (left in the file)" in err and "reading the input by parts and cutting it into tiles:" in err
    assert output.read_bytes() == reference.read_bytes()


@pytest.mark.parametrize("stage", ["round 2", "gathering the levels above the tiles"])
def test_killed_worker_with_kept_tiles_changes_nothing(cluster, generated, binary, tmp_path, monkeypatch, capsys, stage):
    """The first round's tiles kept on the workers for the rounds after (kept_tiles): a worker
    killed while the second round's tiles run, or while a later round gathers the levels above the
    tiles from them, loses the batches it held. Dask builds them again from the tasks that made
    them, from the input up: the same bytes."""
    from toposimp import dask as toposimp_dask

    client, workers = cluster
    lines, places = generated
    arguments = [str(lines), "-p", str(places), "--keep", "30%", *SAME_DATE]
    reference = tmp_path / "reference.gpkg"
    done = subprocess.run([binary, "map", *arguments, "-o", str(reference)], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    pids = client.run(os.getpid)
    killed, seen = {}, []
    gather, run_direct = toposimp_dask._Tasks._gather, toposimp_dask._Tasks._run_direct

    def kill(client_, what):
        seen.append(what)
        # (The second round's tiles; or the 40th wave of questions from the levels above, past the
        # first round's.)
        if not killed and what.startswith(stage) and (stage == "round 2" or seen.count(what) == 40):
            held = client_.has_what()  # (the kept batches among what the workers hold)
            for address, pid in pids.items():
                if pid in [w.pid for w in workers] and held.get(address):
                    killed["address"] = address
                    os.kill(pid, signal.SIGKILL)
                    break

    def gather_killing(self, client_, futures, what, on_progress=None, each=None, release=True):
        kill(client_, what)
        return gather(self, client_, futures, what, on_progress, each, release)

    def run_direct_killing(self, client_, function, *arguments, what, workers):
        kill(client_, what)
        return run_direct(self, client_, function, *arguments, what=what, workers=workers)

    monkeypatch.setattr(toposimp_dask._Tasks, "_gather", gather_killing)
    monkeypatch.setattr(toposimp_dask._Tasks, "_run_direct", run_direct_killing)
    output = tmp_path / "kept.gpkg"
    status = toposimp_dask.run([*arguments, "-o", str(output), "-v"], client=client, tile_level=1, local_budget=0, quiet=True,
                               first_round="workers", kept_tiles=True)
    assert killed, f"no worker held anything at {stage!r}"
    assert status == 0 and output.read_bytes() == reference.read_bytes()
    # The questions that change nothing asked straight of the workers, and through tasks from the
    # loss on.
    waves = re.search(r"the kept tiles' questions: (\d+) waves asked straight of the workers, (\d+) through tasks", capsys.readouterr().err)
    assert waves, "no count of the kept tiles' questions"
    assert int(waves[1]) >= 1 and int(waves[2]) >= 1, waves[0]
    workers.append(client.start_worker())  # (three again for the tests after)
    client.wait_for_workers(3, timeout=60)


def test_input_changed_under_the_workers_stops_the_run(cluster, generated_shapefiles, tmp_path, monkeypatch, capsys):
    """The input changed after the command read it, before the workers read their parts: the run
    stops with the reason (exit 2, the command line's message), nothing written."""
    import shutil

    from toposimp import dask as toposimp_dask

    client, _ = cluster
    for extension in (".shp", ".shx", ".dbf"):
        shutil.copy(generated_shapefiles[0].with_suffix(extension), tmp_path / ("lines" + extension))
    lines = tmp_path / "lines.shp"
    first_round = toposimp_dask._Tasks._first_round

    def touched_first(self, steps, plan, options):
        stat = lines.stat()
        os.utime(lines, ns=(stat.st_atime_ns, stat.st_mtime_ns + 10**9))
        return first_round(self, steps, plan, options)

    monkeypatch.setattr(toposimp_dask._Tasks, "_first_round", touched_first)
    output = tmp_path / "out.shp"
    capsys.readouterr()
    status = toposimp_dask.main(["map", str(lines), "--keep", "10%", "-o", str(output), "--first-round", "workers", "-q",
                                 "--scheduler", client.scheduler.address])
    err = capsys.readouterr().err
    assert status == 2, err
    assert f"toposimp.dask: error: '{lines}' cannot be read here as it was when the map was read" in err
    assert "--send-input" in err and "no output written" in err and "Traceback" not in err
    assert not output.exists()


def test_a_task_whose_workers_keep_dying_stops_the_run(cluster, generated, tmp_path, monkeypatch):
    """A round's task sent straight to a worker and lost with it is sent again, but not without end:
    past Dask's allowed failures (distributed.scheduler.allowed-failures), the run stops with a
    message (the command's exit status 2) and writes nothing, as Dask's KilledWorker stops a task
    that kills its workers. (Every task counts as lost here; without the bound the run never ends.)"""
    import dask.config
    from toposimp import UsageError, dask as toposimp_dask

    client, _ = cluster
    polygons_and_lines, places = generated
    sent = []
    straight_submit = toposimp_dask._StraightSender.submit

    def counted_submit(self, *arguments):
        sent.append(1)
        return straight_submit(self, *arguments)

    monkeypatch.setattr(toposimp_dask._StraightSender, "submit", counted_submit)
    monkeypatch.setattr(toposimp_dask._StraightSender, "lost", lambda self, future: True)
    output = tmp_path / "never.gpkg"
    with dask.config.set({"distributed.scheduler.allowed-failures": 2}), pytest.raises(UsageError, match="lost its Dask worker 3 times"):
        toposimp_dask.run([str(polygons_and_lines), "-p", str(places), "--keep", "30%", "-o", str(output), "-q"],
                          client=client, tile_level=1, local_budget=0)
    assert not output.exists() and not list(tmp_path.iterdir())
    assert len(sent) >= 3


def test_several_tile_levels_give_the_same_bytes(cluster, generated, binary, tmp_path):
    from toposimp import dask as toposimp_dask

    client, _ = cluster
    polygons_and_lines, places = generated
    # (--keep 10%: more than any run can remove, so run as --max; the others in rounds.)
    for target in (["--max"], ["--max-area", "0.002"], ["--keep-points", "30000"], ["--remove-points", "5000"], ["--keep", "10%"]):
        arguments = [str(polygons_and_lines), "-p", str(places), *target, *SAME_DATE]
        reference = tmp_path / "reference.gpkg"
        subprocess.run([binary, "map", *arguments, "-o", str(reference), "--overwrite"], check=True, capture_output=True)
        # (top_runs: the levels above the tiles over a subset of the live map, its runs of 1 at
        # first, too short somewhere, or of 4; kept: the first round's tiles kept on the workers,
        # the rounds after from them, the subsets gathered from them.)
        for level, first_round, top_runs, kept in ((0, "workers", 0, False), (2, "here", 0, False), (-1, "workers", 0, False),
                                                   (2, "here", 1, False), (-1, "workers", 4, False), (1, "workers", 1, True),
                                                   (2, "workers", 0, True)):
            output = tmp_path / f"level{level}.gpkg"
            assert toposimp_dask.run([*arguments, "-o", str(output), "--overwrite"], client=client, tile_level=level,
                                     local_budget=0 if level != 2 else 2000, quiet=True, first_round=first_round, top_runs=top_runs,
                                     kept_tiles=kept) == 0
            assert output.read_bytes() == reference.read_bytes(), \
                f"{target}, tile level {level}, first round {first_round}, top runs {top_runs}, kept tiles {kept}"


def stages_seen(monkeypatch):
    """The stages the run waits for (what _Tasks._gather is told), in a list the run fills."""
    from toposimp import dask as toposimp_dask

    stages = []
    gather = toposimp_dask._Tasks._gather

    def gather_seen(self, client_, futures, what, on_progress=None, each=None, release=True):
        stages.append(what)
        return gather(self, client_, futures, what, on_progress, each, release)

    monkeypatch.setattr(toposimp_dask._Tasks, "_gather", gather_seen)
    return stages


def test_kept_tiles_chosen_by_the_memory_here(cluster, generated, binary, tmp_path, monkeypatch, capsys):
    """--first-round workers without --kept-tiles: the first round's tiles stay on the workers when
    the live map after it would take more than half the memory left here, else the live map comes
    here (-v says which, and why); the same bytes either way."""
    from toposimp import dask as toposimp_dask

    client, _ = cluster
    polygons_and_lines, places = generated
    arguments = [str(polygons_and_lines), "-p", str(places), "--keep", "30%", *SAME_DATE]
    reference = tmp_path / "reference.gpkg"
    subprocess.run([binary, "map", *arguments, "-o", str(reference)], check=True, capture_output=True)
    stages = stages_seen(monkeypatch)
    for room, kept in ((2**20, True), (2**45, False), (None, False)):
        monkeypatch.setattr(toposimp_dask, "_memory_here", lambda: room)
        stages.clear()
        output = tmp_path / f"auto{kept}{room}.gpkg"
        assert toposimp_dask.run([*arguments, "-o", str(output), "-v"], client=client, tile_level=1, local_budget=0, quiet=True,
                                 first_round="workers") == 0
        err = capsys.readouterr().err
        assert ("its tiles stay on the workers (--kept-tiles)" in err) == kept, err
        assert ("it comes here" in err) == (not kept), err
        assert ("no measure of the memory left here" in err) == (room is None)
        assert ("keeping the tiles" in stages) == kept, stages
        assert output.read_bytes() == reference.read_bytes(), f"memory left {room}"
        if kept:  # (every worker there: every question that changes nothing asked straight of them)
            waves = re.search(r"the kept tiles' questions: (\d+) waves asked straight of the workers, (\d+) through tasks", err)
            assert waves and int(waves[1]) >= 10 and int(waves[2]) == 0, err[-2000:]


def test_first_round_chosen_by_the_input_size(cluster, generated, binary, tmp_path, monkeypatch, capsys):
    """No first_round given: the first round runs on the workers, the input read by parts there,
    when the input read here whole could take more than half the memory left here (about 5 times
    its size on disk), else here; -v says which and why; the same bytes either way."""
    from toposimp import dask as toposimp_dask

    client, _ = cluster
    polygons_and_lines, places = generated
    arguments = [str(polygons_and_lines), "-p", str(places), "--keep", "30%", *SAME_DATE]
    reference = tmp_path / "reference.gpkg"
    subprocess.run([binary, "map", *arguments, "-o", str(reference)], check=True, capture_output=True)
    size = polygons_and_lines.stat().st_size
    stages = stages_seen(monkeypatch)
    for room, workers in ((8 * size, True), (12 * size, False), (None, False)):
        monkeypatch.setattr(toposimp_dask, "_memory_here", lambda: room)
        stages.clear()
        output = tmp_path / f"auto{workers}{room}.gpkg"
        assert toposimp_dask.run([*arguments, "-o", str(output), "-v"], client=client, tile_level=1, local_budget=0, quiet=True) == 0
        err = capsys.readouterr().err
        assert f"the input, {size / 2**20:.0f} MiB on disk" in err, err
        assert ("its first round runs on the workers, which read it by parts" in err) == workers, err
        assert ("it is read here (--first-round here)" in err) == (not workers), err
        assert ("vertices (left in the file)" in err) == workers
        assert ("reading the input by parts and cutting it into tiles" in stages) == workers, stages
        assert output.read_bytes() == reference.read_bytes(), f"memory left {room}"


def test_memory_here_reads_the_machine_and_its_cgroup_limits(tmp_path):
    """_memory_here: the machine's MemAvailable, or less where a cgroup v2 or v1 limit leaves less;
    no limit ("max", or v1's number near 2^63) changes nothing; nothing readable, None."""
    from toposimp import dask as toposimp_dask

    def machine(name, available_kib, cgroup, files):
        root = tmp_path / name
        (root / "proc/self").mkdir(parents=True)
        if available_kib is not None:
            (root / "proc/meminfo").write_text(f"MemTotal:       24000000 kB\nMemAvailable:   {available_kib} kB\n")
        (root / "proc/self/cgroup").write_text(cgroup)
        for path, text in files.items():
            (root / path).parent.mkdir(parents=True, exist_ok=True)
            (root / path).write_text(text)
        return str(root)

    gib = 2**30
    assert toposimp_dask._memory_here(machine("none", 8 * 2**20, "0::/\n", {"sys/fs/cgroup/memory.max": "max\n"})) == 8 * gib
    assert toposimp_dask._memory_here(machine("v2", 8 * 2**20, "0::/job/7\n", {
        "sys/fs/cgroup/job/7/memory.max": f"{3 * gib}\n", "sys/fs/cgroup/job/7/memory.current": f"{gib}\n"})) == 2 * gib
    assert toposimp_dask._memory_here(machine("v1", 8 * 2**20, "4:memory:/slurm/job1\n1:cpu:/\n0::/\n", {
        "sys/fs/cgroup/memory/slurm/job1/memory.limit_in_bytes": f"{5 * gib}\n",
        "sys/fs/cgroup/memory/slurm/job1/memory.usage_in_bytes": f"{4 * gib}\n"})) == gib
    assert toposimp_dask._memory_here(machine("v1free", 8 * 2**20, "4:memory:/x\n", {
        "sys/fs/cgroup/memory/x/memory.limit_in_bytes": "9223372036854771712\n",
        "sys/fs/cgroup/memory/x/memory.usage_in_bytes": "6011252736\n"})) == 8 * gib
    assert toposimp_dask._memory_here(machine("above", 1 * 2**20, "0::/a\n", {
        "sys/fs/cgroup/a/memory.max": f"{3 * gib}\n", "sys/fs/cgroup/a/memory.current": "0\n"})) == gib
    assert toposimp_dask._memory_here(machine("cgroup only", None, "0::/a\n", {
        "sys/fs/cgroup/a/memory.max": f"{3 * gib}\n", "sys/fs/cgroup/a/memory.current": "0\n"})) == 3 * gib
    assert toposimp_dask._memory_here(str(tmp_path / "nothing")) is None


def test_budget_selected_pass_by_pass_on_the_workers(cluster, generated, binary, tmp_path, monkeypatch):
    """--first-round workers with no bucket small enough to gather: the bound found by every
    pass over the tiles' keys and the ids at the key, the same bytes."""
    from toposimp import dask as toposimp_dask

    client, _ = cluster
    polygons_and_lines, places = generated
    arguments = [str(polygons_and_lines), "-p", str(places), "--keep", "35%", *SAME_DATE]
    reference = tmp_path / "reference.gpkg"
    subprocess.run([binary, "map", *arguments, "-o", str(reference)], check=True, capture_output=True)
    monkeypatch.setattr(toposimp_dask, "PAIRS_GATHERED", 0)
    output = tmp_path / "dask.gpkg"
    assert toposimp_dask.run([*arguments, "-o", str(output)], client=client, tile_level=2, quiet=True, first_round="workers") == 0
    assert output.read_bytes() == reference.read_bytes()


def test_bad_input_stops_with_the_command_line_message(cluster, tmp_path, capsys):
    from toposimp import dask as toposimp_dask

    client, _ = cluster
    broken = tmp_path / "broken.geojson"
    broken.write_text('{"type": "FeatureCollection", "features": [{"type": "Feature", "properties": {}, '
                      '"geometry": {"type": "LineString", "coordinates": [[0, 0], [1, "x"]]}}]}')
    output = tmp_path / "out.gpkg"
    status = toposimp_dask.run([str(broken), "-o", str(output), "--max"], client=client, quiet=True)
    assert status == 2
    assert "broken.geojson" in capsys.readouterr().err
    assert not output.exists()
    assert not list(tmp_path.glob("*.tmp*")) and sorted(p.name for p in tmp_path.iterdir()) == ["broken.geojson"]


def test_worker_without_the_package_is_named(tmp_path):
    """A worker that cannot import toposimp: exit 2, a message naming it and what to do, no output
    (not a traceback from inside a task)."""
    address_file = tmp_path / "scheduler.json"
    bare = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    processes = [subprocess.Popen([sys.executable, "-m", "distributed.cli.dask_scheduler", "--host", "127.0.0.1", "--port", "0",
                                   "--scheduler-file", str(address_file), "--no-dashboard"],
                                  stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, cwd=tmp_path, env=bare)]
    try:
        deadline = time.monotonic() + 60
        while not address_file.exists() and time.monotonic() < deadline:
            time.sleep(0.1)
        processes.append(subprocess.Popen([sys.executable, "-m", "distributed.cli.dask_worker", "--scheduler-file", str(address_file),
                                           "--nthreads", "1", "--no-nanny", "--no-dashboard", "--local-directory", str(tmp_path / "w")],
                                          stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, cwd=tmp_path, env=bare))
        with distributed.Client(scheduler_file=str(address_file)) as client:
            client.wait_for_workers(1, timeout=60)
            address = client.scheduler.address
        output = tmp_path / "out.gpkg"
        done = subprocess.run([sys.executable, "-m", "toposimp.dask", "map", str(ROOT / "testdata" / "nh_borders.gpkg"), "-o", str(output),
                               "--keep", "10%", "--scheduler", address, "--local-budget", "0", "--tile-level", "1"],
                              capture_output=True, text=True, timeout=120)
        assert done.returncode == 2, done.stderr
        assert "cannot import toposimp" in done.stderr and "PYTHONPATH" in done.stderr
        assert "Traceback" not in done.stderr
        assert not output.exists()
    finally:
        for process in processes:
            process.kill()
            process.wait()


def test_unreachable_scheduler_is_a_usage_error(tmp_path):
    """--scheduler where none listens: exit 2 and a message naming it, no output, no traceback."""
    import socket

    with socket.socket() as probe:  # a port nobody listens on
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]
    output = tmp_path / "out.gpkg"
    env = dict(os.environ, DASK_DISTRIBUTED__COMM__TIMEOUTS__CONNECT="2s")
    done = subprocess.run([sys.executable, "-m", "toposimp.dask", "map", str(ROOT / "testdata" / "nh_borders.gpkg"), "-o", str(output),
                           "--keep", "10%", "--scheduler", f"tcp://127.0.0.1:{port}", "--local-budget", "0", "--tile-level", "1"],
                          capture_output=True, text=True, timeout=120, env=env)
    assert done.returncode == 2, done.stderr
    assert f"cannot reach the Dask scheduler at tcp://127.0.0.1:{port}" in done.stderr
    assert "Traceback" not in done.stderr
    assert not output.exists()


def test_the_command_ends_with_its_streams_flushed_and_atexit_run():
    """The command ends without Python's teardown (toposimp.dask._exit): first the atexit handlers
    run and what is left in the standard streams' buffers goes out, through pipes too; the status
    is main()'s."""
    script = ("import atexit, sys\n"
              "from toposimp import dask\n"
              "atexit.register(lambda: sys.stderr.write('atexit ran'))\n"
              "sys.stdout.write('x' * 100)\n"
              "dask._exit(3)\n")
    buffered = {name: value for name, value in os.environ.items() if name != "PYTHONUNBUFFERED"}
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=120, env=buffered)
    assert done.returncode == 3, done.stderr
    assert done.stdout == "x" * 100
    assert done.stderr.endswith("atexit ran"), done.stderr


def test_bad_input_does_not_wait_for_an_unreachable_scheduler(tmp_path):
    """The command connects to --scheduler while the engine reads; a run that stops on its input
    first reports that at once, without waiting out Dask's connect timeout (60 s here)."""
    import socket

    with socket.socket() as probe:  # a port nobody listens on (a host that never answers, as far as this run sees)
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]
        probe.listen(0)  # (bound and listening, never accepting: the connect hangs until its timeout)
        bad = tmp_path / "bad.geojson"
        bad.write_text('{"type": "FeatureCollection", "features": [{"type": "Feature", "properties": {}, '
                       '"geometry": {"type": "LineString", "coordinates": [[0, 0], [1]]}}]}')
        output = tmp_path / "out.gpkg"
        env = dict(os.environ, DASK_DISTRIBUTED__COMM__TIMEOUTS__CONNECT="60s")
        start = time.monotonic()
        done = subprocess.run([sys.executable, "-m", "toposimp.dask", "map", str(bad), "-o", str(output), "--keep", "10%",
                               "--scheduler", f"tcp://127.0.0.1:{port}"], capture_output=True, text=True, timeout=120, env=env)
        seconds = time.monotonic() - start
    assert done.returncode != 0 and "Traceback" not in done.stderr, done.stderr
    assert "bad.geojson" in done.stderr, done.stderr
    assert seconds < 30, (seconds, done.stderr)
    assert not output.exists()


def test_levels_and_published_precision(cluster, generated, binary, tmp_path):
    """--levels (each level a run in parts on the previous one) and --decimals: the same files."""
    from toposimp import dask as toposimp_dask

    client, _ = cluster
    polygons_and_lines, places = generated
    arguments = [str(polygons_and_lines), "-p", str(places), "--levels", "30%,10%,3%", "--decimals", "2", *SAME_DATE]
    (tmp_path / "single").mkdir()
    (tmp_path / "dask").mkdir()
    subprocess.run([binary, "map", *arguments, "-o", str(tmp_path / "single" / "out_{level}.gpkg")], check=True, capture_output=True)
    assert toposimp_dask.run([*arguments, "-o", str(tmp_path / "dask" / "out_{level}.gpkg")], client=client, tile_level=2,
                             local_budget=0, quiet=True) == 0
    names = sorted(p.name for p in (tmp_path / "single").iterdir())
    assert len(names) == 3
    assert sorted(p.name for p in (tmp_path / "dask").iterdir()) == names
    for name in names:
        assert (tmp_path / "dask" / name).read_bytes() == (tmp_path / "single" / name).read_bytes(), name


def test_command_line(generated, binary, tmp_path):
    """The module as a command: its own LocalCluster, toposimp map's options and --json."""
    polygons_and_lines, places = generated
    arguments = [str(polygons_and_lines), "-p", str(places), "--keep", "30%", *SAME_DATE]
    reference = tmp_path / "reference.gpkg"
    subprocess.run([binary, "map", *arguments, "-o", str(reference)], check=True, capture_output=True)
    output = tmp_path / "dask.gpkg"
    done = subprocess.run([sys.executable, "-m", "toposimp.dask", "map", *arguments, "-o", str(output), "--workers", "2",
                           "--tile-level", "2", "--local-budget", "0", "--json", "--first-round", "workers", "--top-runs", "3"],
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    report = json.loads(done.stdout)
    assert report["command"] == "map" and report["vertices_out"] < report["vertices_in"]
    assert "round 2, tiles of level 2:" in done.stderr and "tasks done" in done.stderr
    assert "searching the tiles for crossings:" in done.stderr  # (the first round's stages on the workers)
    assert output.read_bytes() == reference.read_bytes()
    usage = subprocess.run([sys.executable, "-m", "toposimp.dask", "--help"], capture_output=True, text=True)
    assert usage.returncode == 0 and all(option in usage.stdout for option in ("--scheduler", "--first-round", "--send-input", "--top-runs",
                                                                               "--kept-tiles"))
    negative = subprocess.run([sys.executable, "-m", "toposimp.dask", "map", *arguments, "-o", str(tmp_path / "no.gpkg"), "--top-runs",
                               "-1"], capture_output=True, text=True)
    assert negative.returncode == 2 and "--top-runs" in negative.stderr and not (tmp_path / "no.gpkg").exists()
    wrong = subprocess.run([sys.executable, "-m", "toposimp.dask", "map", *arguments, "-o", str(tmp_path / "no.gpkg"), "--first-round",
                            "nowhere"], capture_output=True, text=True)
    assert wrong.returncode == 2 and "--first-round" in wrong.stderr and not (tmp_path / "no.gpkg").exists()
    here = subprocess.run([sys.executable, "-m", "toposimp.dask", "map", *arguments, "-o", str(tmp_path / "no.gpkg"), "--first-round", "here",
                           "--kept-tiles"], capture_output=True, text=True)
    assert here.returncode == 2 and "--kept-tiles needs --first-round workers" in here.stderr and not (tmp_path / "no.gpkg").exists()


def test_command_line_asks_for_huge_pages(generated, binary, tmp_path):
    """`python3 -m toposimp.dask` started without glibc.malloc.hugetlb in GLIBC_TUNABLES runs
    with it (the command's process started again with it, as its workers); one the user set is
    kept. Its LocalCluster of one worker gives each task all the cores here (-v says so), and the
    bytes are toposimp map's."""
    import os

    polygons_and_lines, _ = generated
    arguments = [str(polygons_and_lines), "--keep", "20%", *SAME_DATE]
    reference = tmp_path / "reference.gpkg"
    subprocess.run([binary, "map", *arguments, "-o", str(reference)], check=True, capture_output=True)
    cores = len(os.sched_getaffinity(0))
    environment = {name: value for name, value in os.environ.items() if name != "GLIBC_TUNABLES"}
    for tunables, asked in ((None, True), ("glibc.malloc.check=0", True), ("glibc.malloc.hugetlb=0", False)):
        if tunables is not None:
            environment["GLIBC_TUNABLES"] = tunables
        output = tmp_path / ("out%s.gpkg" % len(str(tunables)))
        done = subprocess.run([sys.executable, "-m", "toposimp.dask", "map", *arguments, "-o", str(output), "--workers", "1", "-v"],
                              capture_output=True, text=True, timeout=300, env=environment)
        assert done.returncode == 0, done.stderr
        assert ("transparent huge pages asked for" in done.stderr) == asked, (tunables, done.stderr[:2000])
        # (The command's heap thresholds with them, where the command asked.)
        assert ("glibc.malloc.mmap_threshold=33554432" in done.stderr) == asked, (tunables, done.stderr[:2000])
        assert f"toposimp.dask: debug: {cores} thread(s) a task" in done.stderr, done.stderr[-3000:]
        assert output.read_bytes() == reference.read_bytes(), tunables


def test_the_command_restarts_before_the_engine_loads():
    """The package restarts `python3 -m toposimp.dask` itself (glibc reads its tunables when a
    process starts), before the engine and numpy load: it knows the command from the interpreter's
    command line, whatever options come before -m, and no other."""
    from toposimp import _launch

    for argv, runs in ((["python3", "-m", "toposimp.dask", "map", "in.shp"], True),
                       (["python3", "-X", "importtime", "-W", "error", "-u", "-m", "toposimp.dask"], True),
                       (["python3", "-mtoposimp.dask"], True),
                       (["python3", "-m", "toposimp"], False),
                       (["python3", "-m", "toposimp.dask2"], False),
                       (["python3", "script.py", "-m", "toposimp.dask"], False),
                       (["python3", "-c", "import toposimp", "-m", "toposimp.dask"], False),
                       (["python3", "-m"], False),
                       (["python3"], False)):
        assert _launch.runs_module(argv, "toposimp.dask") == runs, argv
    assert _launch.command_tunables("") == \
        "glibc.malloc.hugetlb=1:glibc.malloc.mmap_threshold=33554432:glibc.malloc.trim_threshold=268435456"
    assert _launch.command_tunables("glibc.malloc.trim_threshold=0:glibc.malloc.hugetlb=0") == \
        "glibc.malloc.trim_threshold=0:glibc.malloc.hugetlb=0:glibc.malloc.mmap_threshold=33554432"
    # In a restarted command, the engine was not loaded before the restart: run with a tunable
    # set, the first process would have loaded it and printed nothing.
    done = subprocess.run([sys.executable, "-X", "importtime", "-m", "toposimp.dask", "--help"], capture_output=True, text=True,
                          env={name: value for name, value in os.environ.items() if name != "GLIBC_TUNABLES"}, timeout=120)
    assert done.returncode == 0, done.stderr
    loads = [line for line in done.stderr.splitlines() if line.rstrip().endswith("toposimp._toposimp")]
    assert len(loads) == 1, done.stderr[-3000:]


def test_quiet_run_with_big_tiles_prints_nothing(cluster, binary, tmp_path):
    """-q: nothing on stderr, also when a task's tiles pass Dask's 5 MiB "large object" mark (the
    tiles travel with their tasks on purpose; Dask's advice to scatter them is not for the user)."""
    client, _ = cluster
    # One tile over the whole map: 320 k vertices, over 5 MiB as the task's arguments.
    lines, _ = generate_map.generate(tmp_path / "big", cells=4, edge_vertices=8000, rivers=1, river_steps=10, roads=1,
                                     points=10, seed=5)
    arguments = [str(lines), "--keep", "10%", "-q", *SAME_DATE]
    reference = tmp_path / "reference.gpkg"
    subprocess.run([binary, "map", *arguments, "-o", str(reference)], check=True, capture_output=True)
    output = tmp_path / "dask.gpkg"
    done = subprocess.run([sys.executable, "-m", "toposimp.dask", "map", *arguments, "-o", str(output),
                           "--scheduler", client.scheduler.address, "--tile-level", "99", "--local-budget", "0"],
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    assert done.stderr == ""
    assert output.read_bytes() == reference.read_bytes()


def test_interrupted_run_leaves_nothing(generated, tmp_path):
    """Ctrl-C in the middle (after round 1's tasks): exit 130, a message, no output file."""
    polygons_and_lines, places = generated
    output = tmp_path / "out.gpkg"
    run = subprocess.Popen([sys.executable, "-m", "toposimp.dask", "map", str(polygons_and_lines), "-p", str(places), "-o", str(output),
                            "--keep", "5%", "--workers", "2", "--tile-level", "0", "--local-budget", "0"],
                           stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    for line in run.stderr:
        if "round 1," in line:
            break
    run.send_signal(signal.SIGINT)
    err = run.stderr.read()
    assert run.wait(timeout=120) == 130, err
    assert "interrupted" in err
    assert not output.exists()
    assert list(tmp_path.iterdir()) == []



def test_python_api_with_a_client(cluster, generated):
    """toposimp.simplify(..., client=client): the same geometries as without."""
    import geopandas
    import toposimp

    client, _ = cluster
    polygons_and_lines, places = generated
    layers = {name: geopandas.read_file(polygons_and_lines, layer=name) for name in ("cells", "rivers", "roads")}
    points = geopandas.read_file(places, layer="places")
    from toposimp.dask import Tiles

    def tasks_run():
        return client.run_on_scheduler(lambda dask_scheduler: dask_scheduler.transition_counter)

    alone = toposimp.simplify(layers, keep="40%", points=points)
    before = tasks_run()
    for first_round in ("here", "workers"):
        tiles = Tiles(client, tile_level=2, local_budget=0, first_round=first_round)
        parts = toposimp.simplify(layers, keep="40%", points=points, client=tiles)
        assert tasks_run() > before, "the tiles ran as tasks"
        before = tasks_run()
        assert toposimp.summary(parts["cells"])["vertices_out"] == toposimp.summary(alone["cells"])["vertices_out"]
        for name in layers:
            assert list(parts[name].geometry.to_wkb()) == list(alone[name].geometry.to_wkb()), (name, first_round)
    with pytest.raises(ValueError, match="first_round must be"):
        Tiles(client, first_round="elsewhere")


def test_tiles_fit_the_workers_memory_limit():
    """Under a memory limit the tiles shrink to fit half of it, shared among the tasks a worker runs
    at once (its Dask threads); a limit too small is refused."""
    from toposimp import UsageError
    from toposimp.dask import BYTES_PER_POINT, WORKER_BASE, fitting_tile_points

    class Workers:
        def __init__(self, *limits, threads=None):
            self.limits, self.threads = limits, threads

        def wait_for_workers(self, n, timeout):
            pass

        def scheduler_info(self):
            return {"workers": {f"tcp://w{k}": {"memory_limit": limit, "nthreads": (self.threads or [1] * len(self.limits))[k]}
                                for k, limit in enumerate(self.limits)}}

    assert fitting_tile_points(Workers(0, 0), 1_000_000) == 1_000_000  # no limit
    assert fitting_tile_points(Workers(8 * 2**30), 1_000_000) == 1_000_000
    fits = fitting_tile_points(Workers(8 * 2**30, 512 * 2**20), 1_000_000)  # the smallest limit counts
    assert fits == (256 * 2**20 - WORKER_BASE) // BYTES_PER_POINT
    assert fits * BYTES_PER_POINT + WORKER_BASE <= 256 * 2**20
    # A worker of 4 threads runs 4 tasks at once: its half holds 4 tiles (the worker with the least
    # room a task counts, not the smallest limit).
    shared = fitting_tile_points(Workers(2 * 2**30, 1 * 2**30, threads=[4, 1]), 1_000_000)
    assert shared == int((2**30 - WORKER_BASE) / 4 // BYTES_PER_POINT)
    assert 4 * shared * BYTES_PER_POINT + WORKER_BASE <= 2**30
    assert shared < fitting_tile_points(Workers(2 * 2**30, 1 * 2**30), 1_000_000)
    with pytest.raises(UsageError, match="memory limit"):
        fitting_tile_points(Workers(200 * 2**20), 1_000_000)
    with pytest.raises(UsageError, match=r"the tiles of 8 tasks at once \(its Dask threads\).* or fewer threads"):
        fitting_tile_points(Workers(300 * 2**20, threads=[8]), 1_000_000)
    assert fitting_tile_points(Workers(300 * 2**20), 1_000_000) > 70_000  # (the same limit, a thread)


def test_first_round_on_the_workers_must_fit_their_memory():
    """--first-round workers keeps every tile on the workers between its stages: a map whose tiles
    the workers' limits cannot hold in half of them is refused before any task, with the way out."""
    from toposimp import UsageError
    from toposimp.dask import FIRST_ROUND_BYTES_PER_VERTEX, WORKER_BASE, check_first_round_fits

    class Workers:
        def __init__(self, *limits):
            self.limits = limits

        def scheduler_info(self):
            return {"workers": {f"tcp://w{k}": {"memory_limit": limit} for k, limit in enumerate(self.limits)}}

    check_first_round_fits(Workers(0, 0), 10**9)  # no limits: nothing to check
    room = 2 * (0.5 * 2**30 - WORKER_BASE)
    fits = int(room // FIRST_ROUND_BYTES_PER_VERTEX)
    check_first_round_fits(Workers(2**30, 2**30), fits)
    with pytest.raises(UsageError, match="add workers, raise their limits, or use --first-round here"):
        check_first_round_fits(Workers(2**30, 2**30), fits + 1)
    check_first_round_fits(Workers(2**30, 0), 10**9)  # (a worker without a limit: Dask does not stop it)


def test_quiet_local_cluster_after_a_killed_run(generated, binary, tmp_path):
    """-q with the command's own LocalCluster, after a run whose workers were killed and beside
    another cluster's dashboard: the new workers purge the dead ones' folders, and the scheduler
    finds a port, without a word on the terminal."""
    polygons_and_lines, places = generated
    arguments = [str(polygons_and_lines), "-p", str(places), "--keep", "20%", "-q", *SAME_DATE]
    reference = tmp_path / "reference.gpkg"
    subprocess.run([binary, "map", *arguments, "-o", str(reference)], check=True, capture_output=True)
    # What a killed worker leaves in Dask's temporary folder: its folder and an unheld lock file.
    temporary = tmp_path / "dask-temporary"
    stale = temporary / "dask-worker-space" / "worker-killed"
    stale.mkdir(parents=True)
    (stale.parent / "worker-killed.dirlock").touch()
    output = tmp_path / "dask.gpkg"
    dashboard = socket.socket()  # Dask's dashboard port held, as by another cluster (unless something holds it already)
    try:
        dashboard.bind(("", 8787))
        dashboard.listen()
    except OSError:
        pass
    with dashboard:
        done = subprocess.run([sys.executable, "-m", "toposimp.dask", "map", *arguments, "-o", str(output), "--workers", "1"],
                              capture_output=True, text=True, timeout=300,
                              env=dict(os.environ, DASK_TEMPORARY_DIRECTORY=str(temporary)))
    assert done.returncode == 0, done.stderr
    assert not stale.exists()  # (purged: a new worker met it)
    assert done.stderr == ""
    assert output.read_bytes() == reference.read_bytes()


def test_task_threads_share_each_hosts_cores():
    """Without --task-threads, each task's engine gets its host's cores shared among the Dask
    threads of that host's workers, at least one, the least over the hosts."""
    from toposimp.dask import task_threads_for

    def workers(*hosts_and_threads):
        return {f"tcp://{host}:{4000 + k}": {"host": host, "nthreads": threads} for k, (host, threads) in enumerate(hosts_and_threads)}

    one = workers(("a", 1))
    assert task_threads_for(one, {"tcp://a:4000": 2}) == 2  # (one worker on 2 cores)
    assert task_threads_for(workers(("a", 1), ("a", 1)), {"tcp://a:4000": 2, "tcp://a:4001": 2}) == 1
    assert task_threads_for(workers(("a", 1), ("a", 1), ("a", 1), ("a", 1)), dict.fromkeys(workers(*[("a", 1)] * 4), 2)) == 1
    assert task_threads_for(workers(("a", 2)), {"tcp://a:4000": 8}) == 4  # (two Dask threads in one worker)
    assert task_threads_for(workers(("a", 1), ("b", 1), ("b", 1)), {"tcp://a:4000": 16, "tcp://b:4001": 4, "tcp://b:4002": 4}) == 2
    assert task_threads_for(one, {}) == 1  # (cores unknown)
    assert task_threads_for({}, {}) == 1


def test_tiles_go_straight_only_to_workers_on_this_machine():
    """The command sends a round's tiles to the workers itself only where it surely reaches them:
    every worker on a loopback address or one of this host's; else through the scheduler."""
    import socket
    from toposimp import dask as toposimp_dask

    class Client:
        def __init__(self, *addresses):
            self.addresses = addresses

        def scheduler_info(self):
            return {"workers": {address: {} for address in self.addresses}}

    here = toposimp_dask._workers_here
    assert here(Client("tcp://127.0.0.1:40001", "tcp://127.0.0.1:40002"))
    assert here(Client("tcp://[::1]:40001"))
    assert here(Client(f"tcp://{socket.gethostname()}:40001"))
    assert not here(Client("tcp://127.0.0.1:40001", "tcp://192.0.2.7:40002"))  # (TEST-NET-1: never this host)
    assert not here(Client("tcp://192.0.2.7:40002"))
    assert not here(Client("inproc://10.0.0.1/1234/1"))
    assert not here(Client())


def test_tiles_go_uncompressed_unless_the_user_chose_a_compression():
    """While a round's tiles are sent, Dask's default compression ("auto": lz4) is off; a
    compression the user set is kept; the configuration is as it was afterwards."""
    import dask.config

    from toposimp import dask as toposimp_dask

    before = dask.config.get("distributed.comm.compression")
    assert before == "auto"
    with toposimp_dask._tiles_uncompressed():
        assert dask.config.get("distributed.comm.compression") is False
    assert dask.config.get("distributed.comm.compression") == "auto"
    with dask.config.set({"distributed.comm.compression": "zlib"}):
        with toposimp_dask._tiles_uncompressed():
            assert dask.config.get("distributed.comm.compression") == "zlib"
    assert dask.config.get("distributed.comm.compression") == "auto"
    assert toposimp_dask._given([1, 2]) == [1, 2]
    # (A Dask that would not evaluate the nested task: the task takes its tiles out itself.)
    assert toposimp_dask._run_groups((toposimp_dask._given, []), {}, {}) == []


def test_local_workers_get_huge_pages_their_malloc_and_no_profiler(monkeypatch):
    """local_worker_environment and local_worker_config: what a LocalCluster's workers start with;
    settings of the user's are kept."""
    import ctypes.util

    from toposimp import dask as toposimp_dask

    monkeypatch.setattr(ctypes.util, "find_library", lambda name: None)
    assert toposimp_dask.local_worker_environment("auto", {}) == {"GLIBC_TUNABLES": "glibc.malloc.hugetlb=1"}
    assert toposimp_dask.local_worker_environment("glibc", {"GLIBC_TUNABLES": "glibc.malloc.hugetlb=0"}) == \
        {"GLIBC_TUNABLES": "glibc.malloc.hugetlb=0"}
    assert toposimp_dask.local_worker_config({}) == {"distributed.worker.profile.enabled": False}
    assert toposimp_dask.local_worker_config({"DASK_DISTRIBUTED__WORKER__PROFILE__ENABLED": "True"}) == {}


def test_worker_malloc_is_chosen_as_asked(monkeypatch):
    """--worker-malloc: 'auto' preloads jemalloc where it is installed and leaves glibc's malloc
    where not, 'jemalloc' where it is not installed is a usage error, and an LD_PRELOAD or
    MALLOC_CONF of the user's is kept."""
    import ctypes.util

    from toposimp import UsageError
    from toposimp import dask as toposimp_dask

    monkeypatch.setattr(ctypes.util, "find_library", lambda name: "libjemalloc.so.2" if name == "jemalloc" else None)
    assert toposimp_dask._worker_malloc("auto", {}) == {"LD_PRELOAD": "libjemalloc.so.2", "MALLOC_CONF": "thp:always"}
    assert toposimp_dask._worker_malloc("jemalloc", {"MALLOC_CONF": "narenas:2"}) == {"LD_PRELOAD": "libjemalloc.so.2",
                                                                                     "MALLOC_CONF": "narenas:2"}
    assert toposimp_dask._worker_malloc("auto", {"LD_PRELOAD": "/opt/mine.so"}) == {}
    assert toposimp_dask._worker_malloc("glibc", {}) == {}
    monkeypatch.setattr(ctypes.util, "find_library", lambda name: None)
    assert toposimp_dask._worker_malloc("auto", {}) == {}
    with pytest.raises(UsageError, match="libjemalloc2"):
        toposimp_dask._worker_malloc("jemalloc", {})


def test_local_cluster_workers_run_the_malloc_asked_for(generated, binary, tmp_path):
    """The LocalCluster's workers really run jemalloc's malloc by default where it is installed
    (CI installs Debian's libjemalloc2), glibc's with --worker-malloc glibc, without Dask's
    profiler, and the output is toposimp map's either way."""
    import ctypes.util

    if ctypes.util.find_library("jemalloc") is None:
        pytest.skip("libjemalloc2 is not installed (scripts/setup.sh installs it)")
    polygons_and_lines, _ = generated
    arguments = [str(polygons_and_lines), "--keep", "20%", *SAME_DATE]
    reference = tmp_path / "reference.gpkg"
    subprocess.run([binary, "map", *arguments, "-o", str(reference)], check=True, capture_output=True)
    environment = {name: value for name, value in os.environ.items() if name not in ("LD_PRELOAD", "MALLOC_CONF")}
    for choice, expected in (("auto", "jemalloc"), ("glibc", "glibc")):
        output = tmp_path / f"{choice}.gpkg"
        done = subprocess.run([sys.executable, "-m", "toposimp.dask", "map", *arguments, "-o", str(output), "--workers", "1",
                               "--local-budget", "0", "--worker-malloc", choice, "-v"],
                              capture_output=True, text=True, timeout=300, env=environment)
        assert done.returncode == 0, done.stderr
        assert f"the LocalCluster's workers' malloc: {expected} (--worker-malloc {choice}); Dask's profiler: off" in done.stderr, \
            done.stderr[-2000:]
        assert output.read_bytes() == reference.read_bytes()

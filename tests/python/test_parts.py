"""The engine in parts without Dask: run_command with tile groups run in this process. Each
round's groups come as a sequence that builds group k when it is asked for (the round's tiles
never all exist at once); the output is toposimp map's byte for byte."""
import pathlib
import re

import numpy
import pytest

from conftest import DATA
from toposimp import _toposimp

SAME_DATE = ["--config", "OGR_CURRENT_DATE", "2000-01-01T00:00:00Z"]


def same_tiles(a, b):
    assert len(a) == len(b)
    for one, other in zip(a, b):
        assert one.keys() == other.keys()
        for key in one:
            assert numpy.array_equal(numpy.asarray(one[key]), numpy.asarray(other[key])), key


def test_groups_built_when_asked_for(binary, tmp_path):
    import subprocess

    arguments = [str(DATA / "nh_borders.gpkg"), "-l", "borders", "-p", f"{DATA / 'nh_borders.gpkg'}:places", "--keep", "10%",
                 *SAME_DATE]
    reference = tmp_path / "reference.gpkg"
    subprocess.run([binary, "map", *arguments, "-o", str(reference)], check=True, capture_output=True)

    rounds = []

    def run_groups(groups, plan, options, round_number):
        count = len(groups)
        assert count > 0
        first = groups[0]
        same_tiles(groups[-count], first)  # (built again: the same)
        with pytest.raises(IndexError):
            groups[count]
        rounds.append(groups)
        # (the sequence protocol: iteration ends at the IndexError)
        return [_toposimp.run_tile_group(group, plan, options) for group in groups]

    output = tmp_path / "parts.gpkg"
    status, out, err = _toposimp.run_command(["map", *arguments, "-o", str(output)], run_groups, 2, 0, 0, None, False, False)
    assert status == 0, err
    assert len(rounds) > 1, "a count target runs rounds"
    assert output.read_bytes() == reference.read_bytes()
    with pytest.raises(RuntimeError, match="the round is over"):
        rounds[0][0]


def test_a_tasks_groups_side_by_side_give_the_same_bytes(binary, tmp_path):
    """A task's groups in one call (run_tile_groups, as python/toposimp/dask.py's _run_groups runs
    them): side by side, a thread each, when there are at least as many as the task's threads; the
    output toposimp map's, at 1, 2 and 3 threads a task. A damaged tile among them stops the run."""
    import subprocess

    arguments = [str(DATA / "nh_borders.gpkg"), "-l", "borders", "-p", f"{DATA / 'nh_borders.gpkg'}:places", "--keep", "10%",
                 *SAME_DATE]
    reference = tmp_path / "reference.gpkg"
    subprocess.run([binary, "map", *arguments, "-o", str(reference)], check=True, capture_output=True)
    for threads in (1, 2, 3):
        widths = []

        def run_groups(groups, plan, options, round_number):
            widths.append(len(groups))
            return _toposimp.run_tile_groups(list(groups), plan, dict(options, threads=threads))

        output = tmp_path / f"side_by_side_{threads}.gpkg"  # (tile level 0: 3 to 8 groups a round)
        status, out, err = _toposimp.run_command(["map", *arguments, "-o", str(output)], run_groups, 0, 0, 0, None, False, False)
        assert status == 0, err
        assert max(widths) >= 3, "some rounds should run groups side by side"
        assert output.read_bytes() == reference.read_bytes(), f"{threads} threads a task"

    def damaged(groups, plan, options, round_number):
        groups = [list(group) for group in groups]
        groups[-1][0] = dict(groups[-1][0], vertex_runs=numpy.array([[0, 0]], dtype=numpy.uint32))
        return _toposimp.run_tile_groups(groups, plan, dict(options, threads=2))

    with pytest.raises(ValueError, match="a tile task's data is malformed"):
        _toposimp.run_command(["map", *arguments, "-o", str(tmp_path / "damaged.gpkg")], damaged, 0, 0, 0, None, False, False)
    assert not (tmp_path / "damaged.gpkg").exists()


def test_vertex_ids_travel_as_runs_while_they_are_consecutive(binary, tmp_path):
    """A tile's whole-map vertex ids travel as (first, count) runs of consecutive ids where that takes
    at most half the room (the first round: every vertex live, a piece of a chain is a run), one
    by one where not (later rounds: the live vertices' ids have gaps); either way through a pickle,
    the output is toposimp map's."""
    import pickle
    import subprocess

    arguments = [str(DATA / "nh_borders.gpkg"), "-l", "borders", "-p", f"{DATA / 'nh_borders.gpkg'}:places", "--keep", "10%",
                 *SAME_DATE]
    reference = tmp_path / "reference.gpkg"
    subprocess.run([binary, "map", *arguments, "-o", str(reference)], check=True, capture_output=True)
    kinds = {}

    def run_groups(groups, plan, options, round_number):
        outcomes = []
        for group in groups:
            moved = pickle.loads(pickle.dumps(list(group)))
            for tile in moved:
                assert ("vertex_runs" in tile) != ("vertex_id" in tile)
                if "vertex_runs" in tile:
                    runs = tile["vertex_runs"]
                    assert runs.ndim == 2 and runs.shape[1] == 2 and 4 * len(runs) <= len(tile["vertices"])
                    assert int(runs[:, 1].sum()) == len(tile["vertices"])
                kinds.setdefault(round_number, set()).add("vertex_runs" if "vertex_runs" in tile else "vertex_id")
            outcomes.append(_toposimp.run_tile_group(moved, plan, options))
        return outcomes

    output = tmp_path / "parts.gpkg"
    status, out, err = _toposimp.run_command(["map", *arguments, "-o", str(output)], run_groups, 2, 0, 0, None, False, False)
    assert status == 0, err
    assert kinds[1] == {"vertex_runs"}
    assert "vertex_id" in set().union(*(kinds[r] for r in kinds if r > 1)), kinds
    assert output.read_bytes() == reference.read_bytes()


def test_outcomes_must_match_the_groups(tmp_path):
    """run_groups giving back the wrong number of outcomes stops the run with an error, no output."""
    arguments = [str(DATA / "nh_borders.gpkg"), "-l", "borders", "--max", "-o", str(tmp_path / "out.gpkg")]

    def too_few(groups, plan, options, round_number):
        return [_toposimp.run_tile_group(group, plan, options) for group in groups][1:]

    with pytest.raises(Exception, match="outcome"):
        _toposimp.run_command(["map", *arguments], too_few, 2, 0, 0, None, False, False)
    assert not (tmp_path / "out.gpkg").exists()


def test_tasks_take_the_biggest_groups_first_and_small_ones_together():
    from toposimp.dask import _batches

    points = [5, 900, 40, 40, 1000, 30, 20, 10, 700, 1]
    batches = _batches(points, workers=2)
    assert sorted(k for batch in batches for k in batch) == list(range(len(points)))  # each group once
    assert batches[0] == [4] and batches[1] == [1] and batches[2] == [8]  # the biggest first, alone
    assert len(batches) < len(points)  # the small ones together
    limit = min(max(points), -(-sum(points) // 4))
    assert all(sum(points[k] for k in batch) <= limit or len(batch) == 1 for batch in batches)
    sizes = [sum(points[k] for k in batch) for batch in batches]
    assert max(sizes) == max(points)  # no task holds more than the biggest group
    assert _batches([], workers=3) == []
    assert _batches([7], workers=3) == [[0]]


@pytest.mark.parametrize("damage, message", [
    (lambda t: t.update(vertices=numpy.zeros((len(t["vertices"]), 3))), "'vertices' has the wrong shape"),
    (lambda t: t.update(vertices="not numbers"), "'vertices' is not an array of numbers"),
    (lambda t: t.update(chains=t["chains"][1:]), "the chains do not"),
    (lambda t: t.update(waits=numpy.zeros(4, dtype=numpy.uint32)), "'waits' has the wrong shape"),
    (lambda t: t.update(state=t["state"][1:]), "vertex_id or state is not one per vertex"),
    (lambda t: t.pop("vertex_runs"), "no 'vertex_id'"),
    (lambda t: t.update(vertex_runs=numpy.array([[0, len(t["vertices"]) + 1]], dtype=numpy.uint32)),
     "the vertex id runs do not give one id per vertex"),
    (lambda t: t.update(vertex_runs=numpy.array([[0, len(t["vertices"]) - 1]], dtype=numpy.uint32)),
     "the vertex id runs do not give one id per vertex"),
    (lambda t: t.update(vertex_runs=numpy.array([[2**32 - 1, len(t["vertices"])]], dtype=numpy.uint32)),
     "the vertex id runs do not give one id per vertex"),
    (lambda t: t.update(vertex_runs=numpy.array([[0, 0], [0, len(t["vertices"])]], dtype=numpy.uint32)),
     "the vertex id runs do not give one id per vertex"),
])
def test_a_malformed_tile_stops_the_run(tmp_path, damage, message):
    """A tile task given damaged data (what a worker of another version, or a corrupted transfer,
    could give) stops the run with the reason, and no output is left."""
    arguments = [str(DATA / "nh_borders.gpkg"), "-l", "borders", "--max", "-o", str(tmp_path / "out.gpkg")]

    def damaged(groups, plan, options, round_number):
        outcomes = []
        for group in groups:
            group = list(group)
            group[0] = dict(group[0])
            damage(group[0])
            outcomes.append(_toposimp.run_tile_group(group, plan, options))
        return outcomes

    with pytest.raises(ValueError, match="a tile task's data is malformed: " + message):
        _toposimp.run_command(["map", *arguments], damaged, 2, 0, 0, None, False, False)
    assert not (tmp_path / "out.gpkg").exists()


class FirstRoundHere:
    """run_groups with a first_round: the first round's stages (as python/toposimp/dask.py runs
    them on workers) run here in turn, every tile through a pickle round trip between stages (as
    between workers), the pairs of the budget's bucket gathered after the first pass or not
    (`gather_after`), and `damage(stage, value)` to break one answer."""

    def __init__(self, gather_after=0, damage=None, side_by_side=False):
        import pickle

        self.gather_after, self.damage = gather_after, damage or (lambda stage, value: value)
        self.side_by_side, self.widths = side_by_side, []  # (the groups run by first_runs on 2 threads, as toposimp.dask's tasks do)
        self.moved = lambda tile: pickle.loads(pickle.dumps(tile))
        self.stages = []

    def __call__(self, groups, plan, options, round_number):
        return [_toposimp.run_tile_group(group, plan, options) for group in groups]

    def first_round(self, steps, plan, options):
        level = plan["tile_level"]
        pieces = {}
        self.parts = []
        for k in range(len(steps)):
            part = self.damage("part", steps.part(k))
            self.parts.append(part)
            facts, tiles = _toposimp.first_cut(part, plan, level, options)
            steps.add_facts(self.damage("facts", facts))
            assert [tile.number for tile in tiles] == facts["tiles"].tolist()
            for tile in tiles:
                pieces.setdefault(tile.number, []).append(self.moved(tile))
        searched = {}
        for number in sorted(pieces):
            tile, answer = _toposimp.first_search(pieces[number], options)
            searched[number] = self.moved(self.damage("searched", tile))
            steps.found(answer)
        border = steps.border()
        queued, answers = {}, []
        for number, tile in searched.items():
            tile, answer = _toposimp.first_queue(tile, border, steps.marks, options)
            queued[number] = self.moved(tile)
            answers.append(answer)
            steps.queued(answer["pinned"], answer["queued"])
        tiles = list(queued.values())
        wanted = steps.wanted()
        bound = None
        if wanted > 0:
            def dense(histograms):
                total = numpy.zeros(1 << 16, dtype=numpy.uint64)
                for histogram in histograms:
                    numpy.add.at(total, histogram["digits"], histogram["counts"])
                return total

            selector = _toposimp.DigitSelector(wanted)
            total = dense(a["histogram"] for a in answers)
            selector.counted(total)
            passes = 1
            while selector.counting and passes <= self.gather_after:
                selector.counted(dense([_toposimp.first_histogram(tiles, selector.shift, selector.high)]))
                passes += 1
            if selector.counting:
                pairs = _toposimp.first_pairs_in(tiles, selector.shift + 16, selector.high)
                bound = selector.choose_among(pairs["keys"], pairs["ids"])
                self.stages.append("pairs")
            else:
                bound = selector.choose(_toposimp.first_ids_at(tiles, selector.key))
                self.stages.append("ids")
            steps.bound(*bound)
        holding = [a for a in answers if a["vertices"] > 0]
        groups = []
        if wanted > 0 or not steps.marks:
            groups = steps.groups([(a["number"], steps.marks and tuple(a["smallest"]) <= tuple(bound), a["open"]) for a in holding])
        now = steps.bound_now
        live, outcomes = [], []
        running = set()
        if self.side_by_side:
            self.widths.append(len(groups))
            answers = _toposimp.first_runs([[queued[n] for n in group] for group in groups], [[steps.points(n) for n in group] for group in groups],
                                           steps.marks, now, plan, dict(options, threads=2))
        else:
            answers = [_toposimp.first_run([queued[n] for n in group], [steps.points(n) for n in group], steps.marks, now, plan, options)
                       for group in groups]
        for group, (done, lives) in zip(groups, answers):
            outcomes.extend(done)
            live.extend(lives)
            running.update(group)
        live.extend(_toposimp.first_live(queued[a["number"]], steps.marks, now) for a in holding if a["number"] not in running)
        live = self.damage("live", live)
        steps.add(live[:2], [])  # (in pieces, as they come)
        steps.add(live[2:], outcomes)
        steps.finish()
        self.steps = steps


@pytest.fixture(scope="module")
def crossing_map(tmp_path_factory):
    """A coverage, rivers and roads that cross them, and places: scripts/bench/generate_map.py."""
    import sys

    sys.path.insert(0, str(DATA.parent / "scripts" / "bench"))
    import generate_map

    return generate_map.generate(tmp_path_factory.mktemp("crossing"), cells=6, edge_vertices=12, rivers=12, river_steps=120, roads=4,
                                 points=600, seed=5)


# (--keep 10%: more than any run can remove here, run as --max: no selection.)
@pytest.mark.parametrize("target", [["--keep", "50%"], ["--max"], ["--keep-points", "1500"], ["--max-area", "2e-4"], ["--keep", "10%"]])
@pytest.mark.parametrize("level, gather_after", [(0, 0), (2, 0), (2, 3), (3, 1)])
def test_first_round_by_stages_gives_the_same_bytes(binary, tmp_path, crossing_map, target, level, gather_after):
    """The first round built, searched, selected and run by the stages' tasks (each tile pickled
    between them), the rounds after as usual: toposimp map's output, byte for byte. At level 0 the
    first round's groups run side by side (first_runs)."""
    import subprocess

    lines, places = crossing_map
    arguments = [str(lines), "-p", str(places), *target, *SAME_DATE]
    reference = tmp_path / "reference.gpkg"
    done = subprocess.run([binary, "map", *arguments, "-o", str(reference), "--json"], check=True, capture_output=True, text=True)
    assert '"pinned_by_crossing":0' not in done.stdout  # (crossings to find)
    first = FirstRoundHere(gather_after, side_by_side=level == 0)
    output = tmp_path / "stages.gpkg"
    # (parts of about 700 vertices: several)
    status, out, err = _toposimp.run_command(["map", *arguments, "-o", str(output)], first, level, 700, 0, None, False, False)
    assert status == 0, err
    assert output.read_bytes() == reference.read_bytes()
    if level == 0:
        assert max(first.widths) >= 2, "the first round's groups should have run side by side"
    swept = '"swept_as_max":true' in done.stdout
    assert swept == (target == ["--keep", "10%"])
    if target[0] in ("--keep", "--keep-points"):
        assert first.stages == ([] if swept else ["pairs" if gather_after < 3 else "ids"])
    with pytest.raises(RuntimeError, match="the first round is over"):
        first.steps.border()


@pytest.fixture(scope="module")
def line_shapefile(tmp_path_factory):
    """A plain PolyLine Shapefile of self-crossing walks that cross each other, one- and two-part
    records and null ones (the last two too), and a Shapefile of places."""
    import sys

    sys.path.insert(0, str(DATA.parent / "scripts" / "bench"))
    import generate_map

    out = tmp_path_factory.mktemp("lines")
    rng = numpy.random.default_rng(7)
    writer = generate_map.ShapefileWriter(out / "lines", generate_map.ShapefileWriter.POLYLINE)
    for k in range(32):
        if k % 7 == 3 or k >= 30:
            writer.add_null()
        elif k % 5 == 1:
            writer.add([generate_map.random_walk(rng, 4, 60), generate_map.random_walk(rng, 4, 45)])
        else:
            writer.add([generate_map.random_walk(rng, 4, 120)])
    writer.close()
    places = generate_map.ShapefileWriter(out / "places", generate_map.ShapefileWriter.POINT)
    for x, y in rng.uniform(0, 4, size=(300, 2)):
        places.add((float(x), float(y)))
    places.close()
    return out / "lines.shp", out / "places.shp"


def _same_shapefiles(a, b):
    for extension in (".shp", ".shx", ".dbf"):
        assert a.with_suffix(extension).read_bytes() == b.with_suffix(extension).read_bytes(), extension


def _by_parts_as_toposimp_map(binary, tmp_path, arguments, level, tile_points, suffix=".shp"):
    """toposimp map ARGUMENTS, and the same with the input left in its files and read by the
    first round's tasks (FirstRoundHere): (the parts' run, its stderr, its output, toposimp map's
    output, toposimp map's --json report)."""
    import subprocess

    reference = tmp_path / ("reference" + suffix)
    done = subprocess.run([binary, "map", *arguments, "-o", str(reference), "--json"], check=True, capture_output=True, text=True)
    first = FirstRoundHere()
    output = tmp_path / ("parts" + suffix)
    status, out, err = _toposimp.run_command(["map", *arguments, "-o", str(output), "-v"], first, level, tile_points, 0, None, False,
                                             False, input_on_workers=True)
    assert status == 0, err
    assert "vertices (left in the file)" in err
    return first, err, output, reference, done.stdout


@pytest.mark.parametrize("target", [["--keep", "10%"], ["--max"], ["--keep-points", "900"]])
@pytest.mark.parametrize("level", [0, 2])
def test_first_round_reads_a_shapefile_by_parts(binary, tmp_path, line_shapefile, target, level):
    """A PolyLine Shapefile to a Shapefile, its first round's tasks reading their own records: no
    vertex in the parts handed out (nor in this process: the map is left in the file), the output
    toposimp map's byte for byte."""
    lines, places = line_shapefile
    arguments = [str(lines), "-p", str(places), *target, *SAME_DATE]
    first, err, output, reference, report = _by_parts_as_toposimp_map(binary, tmp_path, arguments, level, 400)
    assert '"pinned_by_crossing":0' not in report  # (crossings to find)
    _same_shapefiles(output, reference)
    assert len(first.parts) > 2
    records = [part["records"] for part in first.parts]
    assert records[0][0] == 0 and records[-1][1] == 32
    assert all(one[1] == other[0] for one, other in zip(records, records[1:]))
    assert all(part["shp"] == str(lines.resolve()) and isinstance(part["vertices"], int) for part in first.parts)


@pytest.fixture(scope="module")
def polygon_shapefile(tmp_path_factory):
    """A plain Polygon Shapefile: a coverage of cells with wavy shared borders, a null record, a
    square with a hole and a flat ring apart; and places among them."""
    import sys

    sys.path.insert(0, str(DATA.parent / "scripts" / "bench"))
    import generate_map

    out = tmp_path_factory.mktemp("polygons")
    rng = numpy.random.default_rng(11)
    horizontal, vertical = generate_map.borders(rng, 5, 30)
    writer = generate_map.ShapefileWriter(out / "cells", generate_map.ShapefileWriter.POLYGON)
    for k, (_, _, ring) in enumerate(generate_map.cell_rings(horizontal, vertical, 5)):
        writer.add([ring[::-1]])  # (outer rings clockwise)
        if k == 7:
            writer.add_null()
    square = numpy.array([[6, 0], [6, 1], [7, 1], [7, 0], [6, 0]], dtype=float)
    hole = numpy.array([[6.25, 0.25], [6.75, 0.25], [6.75, 0.75], [6.25, 0.75], [6.25, 0.25]])
    writer.add([square, hole])
    writer.add([numpy.array([[8, 0], [9, 0], [10, 0], [8, 0]], dtype=float)])
    writer.close()
    places = generate_map.ShapefileWriter(out / "places", generate_map.ShapefileWriter.POINT)
    for x, y in rng.uniform(0, 5, size=(200, 2)):
        places.add((float(x), float(y)))
    places.close()
    return out / "cells.shp", out / "places.shp"


@pytest.mark.parametrize("target", [["--keep", "10%"], ["--max"], ["--remove-points", "500"]])
@pytest.mark.parametrize("level", [0, 1])
def test_first_round_reads_a_polygon_shapefile_by_parts(binary, tmp_path, polygon_shapefile, target, level):
    """A polygon coverage Shapefile to a Shapefile, its first round's tasks making their own arcs
    from their own features: no vertex in the parts handed out (nor in this process), the output
    toposimp map's byte for byte."""
    cells, places = polygon_shapefile
    first, err, output, reference, _ = _by_parts_as_toposimp_map(binary, tmp_path, [str(cells), "-p", str(places), *target, *SAME_DATE],
                                                              level, 300)
    _same_shapefiles(output, reference)
    assert len(first.parts) > 2
    features = [part["features"] for part in first.parts]
    assert features[0][0] == 0 and features[-1][1] == 28
    assert all(one[1] == other[0] for one, other in zip(features, features[1:]))
    assert all(part["polygons_file"] == str(cells.resolve()) and isinstance(part["vertices"], int) for part in first.parts)
    assert sum(len(part["chain_size"]) for part in first.parts) > 25  # (the cells' shared borders are arcs)


@pytest.fixture(scope="module")
def shapefile_folder(tmp_path_factory):
    """A folder of Shapefiles: a coverage of cells, rivers crossing it and each other, roads, and
    places (as the scale run's map, small)."""
    import sys

    sys.path.insert(0, str(DATA.parent / "scripts" / "bench"))
    import generate_map

    out = tmp_path_factory.mktemp("folder")
    generate_map.generate_shapefiles(out, cells=6, edge_vertices=12, rivers=12, river_steps=120, roads=3, points=300, seed=9)
    return out


@pytest.mark.parametrize("output_suffix", [".gpkg", ".fgb"])
def test_first_round_reads_a_folder_of_layers_by_parts(binary, tmp_path, shapefile_folder, output_suffix):
    """Polygon, line and point layers of a folder of Shapefiles, written to one GeoPackage (or the
    polygons to a FlatGeobuf): every layer left in its file but the points (control points, read
    here), the parts of each layer read by their tasks, the output toposimp map's byte for byte."""
    arguments = [str(shapefile_folder), "-l", "rivers", "-l", "places", "-l", "cells", "-l", "roads", "--keep", "10%", *SAME_DATE]
    if output_suffix == ".fgb":  # (one layer a file)
        arguments = [str(shapefile_folder), "-l", "cells", "--keep", "10%", *SAME_DATE]
    first, err, output, reference, _ = _by_parts_as_toposimp_map(binary, tmp_path, arguments, 1, 300, output_suffix)
    assert output.read_bytes() == reference.read_bytes()
    kinds = [("polygons_file" in part, pathlib.Path(part.get("polygons_file", part.get("shp"))).name) for part in first.parts]
    assert (True, "cells.shp") in kinds and ((False, "rivers.shp") in kinds) == (output_suffix == ".gpkg")
    assert kinds == sorted(kinds, key=lambda kind: kind[0])  # (the lines' chains first, then the coverage's arcs)
    assert first.parts[0]["first_chain"] == 0
    assert ("300 control points" in err) == (output_suffix == ".gpkg")
    assert all(one["first_chain"] + len(one["chains"]) == other["first_chain"] for one, other in zip(first.parts, first.parts[1:]))


@pytest.fixture(scope="module")
def geopackage(tmp_path_factory, shapefile_folder):
    """The folder of Shapefiles as one GeoPackage (ogr2ogr: FIDs from 1), a layer each; and a copy
    with features deleted from the cells and the rivers (FIDs with gaps)."""
    import shutil
    import sqlite3
    import subprocess

    out = tmp_path_factory.mktemp("geopackage")
    path = out / "map.gpkg"
    for name in ("cells", "rivers", "roads", "places"):
        subprocess.run(["ogr2ogr", "-f", "GPKG", *(["-update"] if path.exists() else []), str(path), str(shapefile_folder / (name + ".shp"))],
                       check=True, capture_output=True)
    gaps = out / "gaps.gpkg"
    shutil.copy(path, gaps)
    with sqlite3.connect(gaps) as db:
        db.execute("DELETE FROM cells WHERE fid IN (2, 9)")
        db.execute("DELETE FROM rivers WHERE fid IN (1, 5, 6)")
    return path, gaps


@pytest.mark.parametrize("which", ["whole", "gaps"])
@pytest.mark.parametrize("target", [["--keep", "10%"], ["--max"]])
def test_first_round_reads_a_geopackage_by_parts(binary, tmp_path, geopackage, which, target):
    """Polygon, line and point layers of one GeoPackage (its FIDs with gaps or not) to a
    GeoPackage: every layer left in its file but the points (control points, read here), each part
    read by its task by a range of FIDs, the output toposimp map's byte for byte."""
    path = geopackage[0] if which == "whole" else geopackage[1]
    arguments = [str(path), "-l", "rivers", "-l", "places", "-l", "cells", "-l", "roads", *target, *SAME_DATE]
    first, err, output, reference, _ = _by_parts_as_toposimp_map(binary, tmp_path, arguments, 1, 300, ".gpkg")
    assert output.read_bytes() == reference.read_bytes()
    kinds = [("polygons_file" in part, part["layer"]) for part in first.parts]
    assert {kind for kind in kinds} == {(False, "rivers"), (False, "roads"), (True, "cells")}
    assert kinds == sorted(kinds, key=lambda kind: kind[0])  # (the lines' chains first, then the coverage's arcs)
    assert all(part.get("lines_file", part.get("polygons_file")) == str(path.resolve()) for part in first.parts)
    assert all(isinstance(part["vertices"], int) for part in first.parts)
    for layer in ("rivers", "cells"):
        runs = [(part["features"], part["fids"]) for part in first.parts if part["layer"] == layer]
        assert len(runs) > 1
        assert all(one[0][1] == other[0][0] and one[1][1] == other[1][0] for one, other in zip(runs, runs[1:]))
        assert runs[0][0][0] == 0 and runs[0][1][0] == (1 if which == "whole" or layer == "cells" else 2)
    assert "300 control points" in err


@pytest.mark.parametrize("layer", ["rivers", "cells", "folder"])
def test_first_round_reads_a_flatgeobuf_by_parts(binary, tmp_path, shapefile_folder, layer):
    """A FlatGeobuf of lines or of polygons (ogr2ogr: with its index of features), or a folder of
    both, the places as control points, to a FlatGeobuf (the folder: to a GeoPackage): each part
    read by its task, by FID where it does not begin the file; the output toposimp map's byte for
    byte."""
    import subprocess

    folder = tmp_path / "fgb"
    folder.mkdir()
    for name in ("rivers", "cells"):
        subprocess.run(["ogr2ogr", "-f", "FlatGeobuf", "-nlt", "PROMOTE_TO_MULTI", str(folder / (name + ".fgb")),
                        str(shapefile_folder / (name + ".shp"))], check=True, capture_output=True)
    path, suffix, layers = (folder, ".gpkg", ["-l", "rivers", "-l", "cells"]) if layer == "folder" else (folder / (layer + ".fgb"), ".fgb", [])
    arguments = [str(path), *layers, "-p", str(shapefile_folder / "places.shp"), "--keep", "10%", *SAME_DATE]
    first, err, output, reference, _ = _by_parts_as_toposimp_map(binary, tmp_path, arguments, 1, 300, suffix)
    assert output.read_bytes() == reference.read_bytes()
    files = {pathlib.Path(part.get("polygons_file", part.get("lines_file"))).name for part in first.parts}
    assert files == ({"rivers.fgb", "cells.fgb"} if layer == "folder" else {layer + ".fgb"})
    assert len(first.parts) > 2 and all(part["each_by_fid"] for part in first.parts)
    for name in files:
        runs = [part["features"] for part in first.parts if part.get("polygons_file", part.get("lines_file")).endswith(name)]
        assert runs[0][0] == 0 and all(one[1] == other[0] for one, other in zip(runs, runs[1:]))


@pytest.mark.parametrize("which", ["lines", "polygons", "folder", "geopackage"])
@pytest.mark.parametrize("target", [["--keep", "10%"], ["--max"]])
def test_a_topojson_is_written_by_parts(binary, tmp_path, line_shapefile, polygon_shapefile, shapefile_folder, geopackage, which,
                                        target):
    """A TopoJSON of a map left in its files: every arc written from the files read again (a line
    from its feature, a coverage's arc from the rings of the feature that makes it), the objects
    from the plan. Lines with null records and two parts; a coverage with a null record, a hole and
    a flat ring; a folder, and a GeoPackage, of polygon, line and point layers: toposimp map's bytes."""
    layers = ["-l", "rivers", "-l", "places", "-l", "cells", "-l", "roads"]
    arguments = {"lines": [str(line_shapefile[0]), "-p", str(line_shapefile[1])],
                 "polygons": [str(polygon_shapefile[0]), "-p", str(polygon_shapefile[1])],
                 "folder": [str(shapefile_folder), *layers],
                 "geopackage": [str(geopackage[1]), *layers]}[which]
    first, err, output, reference, _ = _by_parts_as_toposimp_map(binary, tmp_path, [*arguments, *target, *SAME_DATE], 1, 300,
                                                              ".topojson")
    assert output.read_bytes() == reference.read_bytes()
    assert len(first.parts) > 2 and '"arcs":[' in output.read_text()
    assert any("polygons_file" in part for part in first.parts) == (which != "lines")


@pytest.mark.parametrize("damage, message", [
    (lambda part: _touched(pathlib.Path(part.get("lines_file", part.get("polygons_file")))) or part,
     "cannot be read here as it was when the map was read"),
    (lambda part: dict(part, fids=(part["fids"][0], part["fids"][1] + 1)), "holds more features than it did|the layer ends before it"),
    (lambda part: dict(part, features=(part["features"][0], part["features"][1] + 1)), "the layer ends before it|holds more"),
    (lambda part: dict(part, fids=(part["fids"][1], part["fids"][0])), "a part's features run backwards"),
])
def test_a_geopackage_part_read_from_a_changed_input_stops_the_run(tmp_path, geopackage, damage, message):
    """A task that reads its features from a GeoPackage that is not the one read here, or by
    another range, stops the run with the reason; nothing is written."""
    import shutil

    shutil.copy(geopackage[0], tmp_path / "map.gpkg")
    first = FirstRoundHere(damage=lambda at, value: damage(value) if at == "part" else value)
    output = tmp_path / "out.gpkg"
    with pytest.raises(ValueError, match=message):
        _toposimp.run_command(["map", str(tmp_path / "map.gpkg"), "-l", "rivers", "--keep", "10%", "-o", str(output)], first, 1, 300, 0,
                              None, False, False, input_on_workers=True)
    assert not output.exists()


def test_a_geopackage_changed_before_writing_leaves_no_output(tmp_path, geopackage):
    """The GeoPackage read again to write the output, a feature deleted since the map was read
    (the same size and time): refused."""
    import os
    import shutil
    import sqlite3

    path = tmp_path / "map.gpkg"
    shutil.copy(geopackage[0], path)

    def change(value):
        stat = path.stat()
        with sqlite3.connect(path) as db:
            db.execute("DELETE FROM rivers WHERE fid = 3")
        db.close()
        os.utime(path, ns=(stat.st_atime_ns, stat.st_mtime_ns))
        assert path.stat().st_size == stat.st_size
        return value

    first = FirstRoundHere(damage=lambda at, value: change(value) if at == "live" else value)
    output = tmp_path / "out.gpkg"
    status, out, err = _toposimp.run_command(["map", str(path), "-l", "rivers", "--keep", "10%", "-o", str(output)], first, 1, 300, 0,
                                             None, False, False, input_on_workers=True)
    assert status == 2
    assert "changed while toposimp ran" in err and "nothing written" in err
    assert not output.exists()


@pytest.mark.parametrize("suffix, dimension", [(".gpkg", "XYZ"), (".gpkg", "XYM"), (".gpkg", "XYZM"), (".shp", "XYZ")])
def test_lines_with_z_or_m_are_read_by_parts(binary, tmp_path, geopackage, suffix, dimension):
    """A GeoPackage's rivers with Z (their id), M or both, beside its cells, or a PolyLineZ
    Shapefile of them: read by parts (Z and M read again where the output is written), the
    output toposimp map's byte for byte."""
    import subprocess

    path = tmp_path / ("zm" + suffix)
    z = ["-zfield", "id"] if "Z" in dimension else []
    subprocess.run(["ogr2ogr", str(path), str(geopackage[0]), "rivers", "-dim", dimension, *z], check=True, capture_output=True)
    arguments = [str(path), "--keep", "10%", *SAME_DATE]
    if suffix == ".gpkg":
        subprocess.run(["ogr2ogr", "-update", str(path), str(geopackage[0]), "cells"], check=True, capture_output=True)
        arguments = [str(path), "-l", "rivers", "-l", "cells", "--keep", "10%", *SAME_DATE]
    first, err, output, reference, _ = _by_parts_as_toposimp_map(binary, tmp_path, arguments, 1, 300, suffix)
    if suffix == ".gpkg":
        assert output.read_bytes() == reference.read_bytes()
        assert any("polygons_file" in part for part in first.parts)
    else:
        _same_shapefiles(output, reference)
    assert any("lines_file" in part for part in first.parts)


def _cells_with_z_and_m(source, path, dimension, per_feature=False):
    """The cells of `source` (a GeoPackage) written to `path` with a Z, an M or both at each
    point: a function of its location (so every ring at a shared location carries the same), or
    with per_feature, the feature's number (so two cells at their shared border do not)."""
    import csv
    import subprocess

    text = path.with_suffix(".csv")
    subprocess.run(["ogr2ogr", "-f", "CSV", str(text), str(source), "cells", "-lco", "GEOMETRY=AS_WKT"], check=True, capture_output=True)
    with open(text, newline="") as f:
        rows = list(csv.DictReader(f))
    tag = {"XYZ": " Z ", "XYM": " M ", "XYZM": " ZM "}[dimension]

    def extra(number, x, y):
        z = float(number) if per_feature else 10 * float(x) + float(y) + 0.125
        m = float(number) if per_feature else float(x) - 2 * float(y)
        return {"XYZ": f"{z!r}", "XYM": f"{m!r}", "XYZM": f"{z!r} {m!r}"}[dimension]

    for number, row in enumerate(rows):
        wkt = re.sub(r"(-?[0-9.eE+-]+) (-?[0-9.eE+-]+)(?=[,)])", lambda p: f"{p[1]} {p[2]} {extra(number, p[1], p[2])}", row["WKT"])
        row["WKT"] = re.sub(r"^(MULTIPOLYGON|POLYGON) ", lambda k: k[1] + tag, wkt)
    with open(text, "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    subprocess.run(["ogr2ogr", str(path), str(text), "-nln", "cells" if path.suffix == ".gpkg" else path.stem, "-oo", "GEOM_POSSIBLE_NAMES=WKT",
                    "-oo", "KEEP_GEOM_COLUMNS=NO", "-a_srs", "EPSG:4326", "-nlt", "POLYGON" + tag.strip()], check=True, capture_output=True)


@pytest.mark.parametrize("per_feature", [False, True])
@pytest.mark.parametrize("suffix, dimension", [(".gpkg", "XYZ"), (".gpkg", "XYM"), (".gpkg", "XYZM"), (".shp", "XYZ")])
def test_polygons_with_z_or_m_are_read_by_parts(binary, tmp_path, geopackage, suffix, dimension, per_feature):
    """Cells with Z, M or both, as a GeoPackage or a PolygonZ Shapefile: a function of the
    location (the same on every ring at a shared location), or each cell's number (rings at a
    shared location differ: there each vertex has the Z and M of the cell that made the border).
    Read by parts (each ring's Z and M read again with it where the output is written), the
    output toposimp map's byte for byte, its Z and M there."""
    import subprocess

    path = tmp_path / ("zm" + suffix)
    _cells_with_z_and_m(geopackage[0], path, dimension, per_feature)
    arguments = [str(path), "--keep", "10%", *SAME_DATE]
    first, err, output, reference, _ = _by_parts_as_toposimp_map(binary, tmp_path, arguments, 1, 300, suffix)
    if suffix == ".gpkg":
        assert output.read_bytes() == reference.read_bytes()
    else:
        _same_shapefiles(output, reference)
    assert len([part for part in first.parts if "polygons_file" in part]) > 1
    info = subprocess.run(["ogrinfo", "-ro", "-al", "-so", str(output)], check=True, capture_output=True, text=True).stdout
    geometry = next(line for line in info.splitlines() if line.startswith("Geometry: "))
    assert ("3D" in geometry) == ("Z" in dimension) and ("Measured" in geometry) == ("M" in dimension), geometry


@pytest.mark.parametrize("target", [["--keep", "10%"], ["--max"]])
def test_real_states_each_at_its_own_height_are_read_by_parts(binary, tmp_path, target):
    """Natural Earth's states (testdata) as XYZM, each state's Z its row number times 1.5 (so the
    rings differ along every shared border) and M 0: read by parts, the output toposimp map's
    byte for byte."""
    import subprocess

    path = tmp_path / "states_zm.gpkg"
    subprocess.run(["ogr2ogr", str(path), str(DATA / "ne_states_slice.gpkg"), "-dialect", "sqlite", "-sql",
                    'SELECT *, CAST(rowid AS REAL) * 1.5 AS height FROM "states"', "-zfield", "height", "-dim", "XYZM", "-nln", "states"],
                   check=True, capture_output=True)
    arguments = [str(path), *target, *SAME_DATE]
    first, err, output, reference, _ = _by_parts_as_toposimp_map(binary, tmp_path, arguments, 1, 2000, ".gpkg")
    assert output.read_bytes() == reference.read_bytes()
    assert len([part for part in first.parts if "polygons_file" in part]) > 1


def _delete_records(dbf_path, records):
    """Marks `records` of a .dbf deleted (as an editor does before the file is packed)."""
    import struct

    with open(dbf_path, "r+b") as dbf:
        header = dbf.read(12)
        header_length, record_length = struct.unpack("<HH", header[8:12])
        for record in records:
            dbf.seek(header_length + record * record_length)
            dbf.write(b"*")


def test_shapefiles_with_deleted_records_are_read_by_parts(binary, tmp_path, shapefile_folder):
    """A folder whose cells (polygons) and rivers (plain PolyLines) have deleted records: both
    left in their files and read by their record numbers (the rivers through OGR, as the decoder
    reads records by index), the output toposimp map's byte for byte."""
    import shutil

    folder = tmp_path / "folder"
    shutil.copytree(shapefile_folder, folder)
    _delete_records(folder / "cells.dbf", [0, 5, 6, 20])
    _delete_records(folder / "rivers.dbf", [2, 3])
    arguments = [str(folder), "-l", "rivers", "-l", "places", "-l", "cells", "--keep", "10%", *SAME_DATE]
    first, err, output, reference, _ = _by_parts_as_toposimp_map(binary, tmp_path, arguments, 1, 300, ".gpkg")
    assert output.read_bytes() == reference.read_bytes()
    fids = {part["layer"]: part["fids"] for part in first.parts if "fids" in part}
    assert set(fids) == {"cells", "rivers"}, first.parts[:2]


@pytest.mark.parametrize("dimension", ["XYZ", "XYM", "XYZM"])
def test_points_with_z_or_m_beside_layers_left_in_their_files(binary, tmp_path, shapefile_folder, dimension):
    """A point layer with Z or M among the layers asked for: the others are left in their files,
    its points are control points held here, written back with their Z and M; the output
    toposimp map's byte for byte."""
    import shutil
    import subprocess

    folder = tmp_path / "folder"
    shutil.copytree(shapefile_folder, folder)
    subprocess.run(["ogr2ogr", str(folder / "heights.shp"), str(folder / "places.shp"), "-dim", dimension, "-nln", "heights"],
                   check=True, capture_output=True)
    arguments = [str(folder), "-l", "rivers", "-l", "heights", "-l", "cells", "--keep", "10%", *SAME_DATE]
    first, err, output, reference, _ = _by_parts_as_toposimp_map(binary, tmp_path, arguments, 1, 300, ".gpkg")
    assert output.read_bytes() == reference.read_bytes()
    assert "the input is read here, whole" not in err
    info = subprocess.run(["ogrinfo", "-ro", "-so", str(output), "heights"], check=True, capture_output=True, text=True).stdout
    geometry = next(line for line in info.splitlines() if line.startswith("Geometry: "))
    assert ("3D" in geometry) == ("Z" in dimension) and ("Measured" in geometry) == ("M" in dimension), geometry


def test_a_folder_with_a_layer_that_cannot_be_left_in_its_file_is_read_whole(tmp_path, shapefile_folder):
    """A folder of FlatGeobufs, one of them without its index of features: every layer is read
    whole, the parts carry their vertices, and -v says why."""
    import subprocess

    folder = tmp_path / "folder"
    folder.mkdir()
    for name, options in (("rivers", []), ("cells", ["-lco", "SPATIAL_INDEX=NO"])):
        subprocess.run(["ogr2ogr", "-f", "FlatGeobuf", str(folder / (name + ".fgb")), str(shapefile_folder / (name + ".shp")), *options],
                       check=True, capture_output=True)
    first = FirstRoundHere()
    output = tmp_path / "whole.gpkg"
    status, out, err = _toposimp.run_command(["map", str(folder), "--keep", "10%", "-o", str(output), "-v"], first, 1, 300, 0, None,
                                             False, False, input_on_workers=True)
    assert status == 0, err
    assert "(left in the file)" not in err
    assert f"the input is read here, whole: '{folder}', layer 'cells': a FlatGeobuf without its index of features" in err, err
    assert all("shp" not in part and "polygons_file" not in part for part in first.parts)


@pytest.mark.parametrize("damage, message", [
    (lambda part: _touched(pathlib.Path(part["polygons_file"])) or part, "cannot be read here as it was when the map was read"),
    (lambda part: dict(part, features=(part["features"][0], part["features"][1] + 1)), "are not the polygons they were"),
    (lambda part: dict(part, node=part["node"] * 0), "are not the polygons they were"),
])
def test_a_polygon_part_read_from_a_changed_input_stops_the_run(tmp_path, polygon_shapefile, damage, message):
    """A task that reads its features from an input that is not the one read here, or with
    another plan, stops the run with the reason; nothing is written."""
    import shutil

    for extension in (".shp", ".shx", ".dbf"):
        shutil.copy(polygon_shapefile[0].with_suffix(extension), tmp_path / ("cells" + extension))
    first = FirstRoundHere(damage=lambda at, value: damage(value) if at == "part" else value)
    output = tmp_path / "out.shp"
    with pytest.raises(ValueError, match=message):
        _toposimp.run_command(["map", str(tmp_path / "cells.shp"), "--keep", "10%", "-o", str(output)], first, 1, 300, 0, None, False,
                              False, input_on_workers=True)
    assert not output.exists()


def test_a_shapefile_left_on_workers_but_sent_without_the_flag(binary, tmp_path, line_shapefile):
    """Without input_on_workers the parts carry their vertices, as for any input."""
    lines, places = line_shapefile
    first = FirstRoundHere()
    status, out, err = _toposimp.run_command(["map", str(lines), "--keep", "10%", "-o", str(tmp_path / "sent.shp")], first, 2, 400, 0,
                                             None, False, False)
    assert status == 0, err
    assert all("shp" not in part and len(part["vertices"]) > 0 for part in first.parts)


def _touched(path):
    import os

    stat = path.stat()
    os.utime(path, ns=(stat.st_atime_ns, stat.st_mtime_ns + 10**9))


@pytest.mark.parametrize("damage, message", [
    (lambda part: _touched(pathlib.Path(part["shp"])) or part, "cannot be read here as it was when the map was read"),
    (lambda part: dict(part, records=(part["records"][0], part["records"][1] + 1)), "are not the lines they were"),
    (lambda part: dict(part, shp=part["shp"] + ".gone"), "cannot be read here as it was when the map was read"),
])
def test_a_part_read_from_a_changed_input_stops_the_run(tmp_path, line_shapefile, damage, message):
    """A task that reads its part from an input that is not the one read here stops the run with
    the reason; nothing is written."""
    import shutil

    for extension in (".shp", ".shx", ".dbf"):
        shutil.copy(line_shapefile[0].with_suffix(extension), tmp_path / ("lines" + extension))
    first = FirstRoundHere(damage=lambda at, value: damage(value) if at == "part" else value)
    output = tmp_path / "out.shp"
    with pytest.raises(ValueError, match=message):
        _toposimp.run_command(["map", str(tmp_path / "lines.shp"), "--keep", "10%", "-o", str(output)], first, 2, 400, 0, None, False,
                              False, input_on_workers=True)
    assert not output.exists()


@pytest.mark.parametrize("input_name, suffix", [("line_shapefile", ".shp"), ("polygon_shapefile", ".topojson")])
def test_an_input_changed_before_writing_leaves_no_output(request, tmp_path, input_name, suffix):
    """The input read again to write the output (a Shapefile's lines; a TopoJSON's arcs, a
    coverage's made again from its rings), changed since the map was read: refused, nothing
    written."""
    import shutil

    given = request.getfixturevalue(input_name)[0]
    for extension in (".shp", ".shx", ".dbf"):
        shutil.copy(given.with_suffix(extension), tmp_path / ("in" + extension))
    path = tmp_path / "in.shp"
    first = FirstRoundHere(damage=lambda at, value: (_touched(path), value)[1] if at == "live" else value)
    output = tmp_path / ("out" + suffix)
    status, out, err = _toposimp.run_command(["map", str(path), "--keep", "10%", "-o", str(output)], first, 2, 300, 0, None, False, False,
                                             input_on_workers=True)
    assert status == 2
    assert f"'{path.resolve()}' changed while toposimp ran" in err
    assert not output.exists() and not list(tmp_path.glob("*.tmp*"))


def _drop_a_live_vertex(live):
    live = [dict(one) for one in live]
    tile = max(live, key=lambda one: len(one["ids"]))
    for key in ("ids", "points", "states"):
        tile[key] = tile[key][1:]
    if len(tile["marked"]):
        tile["marked"] = tile["marked"][1:]
    return live


@pytest.mark.parametrize("stage, damage, message", [
    ("facts", lambda f: dict(f, first_chain=f["first_chain"] + 1), "a part's facts are not the next part's"),
    ("facts", lambda f: dict(f, chains=f["chains"] + 1), "not of the map's chains|not the map's vertices"),
    ("facts", lambda f: dict(f, orientation=numpy.full(len(f["orientation"]), 6, dtype=numpy.int8)), "an orientation is not one"),
    ("facts", lambda f: dict(f, distinct=f["distinct"][1:]), "not one per chain"),
    ("live", lambda live: [dict(one, states=numpy.full(len(one["states"]), 4, dtype=numpy.uint8)) for one in live],
     "a live vertex's state is not one"),
    ("live", lambda live: [dict(one, ids=one["ids"][::-1].copy()) for one in live], "not the map's, in order"),
    ("live", lambda live: [dict(one, points=one["points"][1:]) if len(one["ids"]) else one for one in live], "one point, state"),
    ("live", _drop_a_live_vertex, "do not add up"),
    ("live", lambda live: live[1:], "do not add up"),
    ("live", lambda live: live + live[:1], "do not add up"),
])
def test_a_malformed_first_round_answer_stops_the_run(tmp_path, stage, damage, message):
    """Damaged answers of the first round's tasks stop the run with the reason, no output left."""
    arguments = [str(DATA / "nh_borders.gpkg"), "-l", "borders", "--keep", "20%", "-o", str(tmp_path / "out.gpkg")]
    first = FirstRoundHere(damage=lambda at, value: damage(value) if at == stage else value)
    with pytest.raises(ValueError, match="a tile task's data is malformed: .*(" + message + ")"):
        _toposimp.run_command(["map", *arguments], first, 2, 0, 0, None, False, False)
    assert not (tmp_path / "out.gpkg").exists()


@pytest.mark.parametrize("damage, message", [
    (lambda t: t.update(cut_end=t["cut_end"][1:]), "cut_end is not one per vertex"),
    (lambda t: t.update(passing_id=numpy.zeros(3, dtype=numpy.uint32)), "passing is not two points per passing_id"),
    (lambda t: t.update(keys=numpy.zeros(1, dtype=numpy.uint64)), "keys are not one per queued vertex"),
    (lambda t: t.update(frozen=t["frozen"][1:]), "not one per chain"),
    (lambda t: t.update(chains=t["chains"][1:]), "the chains do not"),
    (lambda t: t.pop("improper"), "no 'improper'"),
])
def test_a_malformed_first_round_tile_is_refused(damage, message):
    """A first-round tile that comes back from a transfer damaged is refused with the reason."""
    import pickle

    part = {"vertices": numpy.array([[0.0, 0.0], [1.0, 0.5], [2.0, 0.0], [3.0, 1.0]]), "chains": numpy.array([[0, 3]], dtype=numpy.uint32),
            "frozen": numpy.zeros(1, dtype=numpy.uint8), "first_vertex": 0, "first_chain": 0}
    plan = {"origin": (0.0, 0.0), "scale": (1.0, 1.0), "cells": (4, 2), "base_scale": (1.0, 1.0), "base_cells": (4, 2), "row_split": 0,
            "shift": 0, "levels": 3}
    options = {"target": 0, "value": 0.5, "weighting": 0.0, "spherical": False, "arithmetic": 0, "threads": 1}
    _, tiles = _toposimp.first_cut(part, plan, 0, options)
    tile, _ = _toposimp.first_search([tiles[0]], options)
    tile, _ = _toposimp.first_queue(tile, numpy.zeros(0, dtype=numpy.uint32), True, options)
    state = tile.__getstate__()
    assert pickle.loads(pickle.dumps(tile)).__getstate__().keys() == state.keys()
    damage(state)
    with pytest.raises(ValueError, match="a tile task's data is malformed: .*" + message):
        type(tile).__new__(type(tile)).__setstate__(state)

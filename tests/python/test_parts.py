"""The engine in parts without Dask: run_command with tile groups run in this process. Each
round's groups come as a sequence that builds group k when it is asked for (the round's tiles
never all exist at once); the output is toposimp map's byte for byte."""
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
    (lambda t: t.pop("vertex_id"), "no 'vertex_id'"),
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

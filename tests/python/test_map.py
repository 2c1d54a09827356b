"""toposimp.simplify and toposimp.check on GeoDataFrames: the round trip keeps everything but the
geometries, the results are the command line's bit for bit, and bad input raises with the
command line's messages."""
import json
import os
import signal
import warnings

import geopandas
import numpy
import pandas
import pytest
import shapely.geometry
import shapely.wkb

import toposimp
from conftest import DATA


def with_geometries(data, replaced):
    """`data` with the geometries at some positions replaced (shapely 1.8 geometries cannot go
    through .loc: numpy takes multi-part ones for sequences)."""
    geometries = list(data.geometry.values)
    for position, geometry in replaced.items():
        geometries[position] = geometry
    out = data.copy()
    out[data.geometry.name] = geopandas.GeoSeries(geometries, index=data.index, crs=data.crs)
    return out


def wkb_list(series):
    return [None if g is None else g.wkb for g in series.values]


def cli_result(run_cli, tmp_path, source, layer, *args, points=None):
    out = tmp_path / f"cli_{len(list(tmp_path.iterdir()))}.gpkg"
    extra = ["--points", f"{points}"] if points else []
    run_cli("map", source, "-l", layer, "-o", out, *extra, *args)
    return geopandas.read_file(out, layer=layer)


TARGETS = [
    ({"keep": 0.1}, ["--keep", "10%"]),
    ({"keep": "3%"}, ["--keep", "3%"]),
    ({"keep_points": 150}, ["--keep-points", "150"]),
    ({"remove_points": 700}, ["--remove-points", "700"]),
    ({"max_area": 2e6}, ["--max-area", "2000000.0"]),
    ({"max": True}, ["--max"]),
    ({"keep": 0.2, "decimals": 0}, ["--keep", "20%", "--decimals", "0"]),
    ({"keep": 0.2, "precision": 50}, ["--keep", "20%", "--precision", "50.0"]),
    ({"keep": 0.1, "weighting": 0.7}, ["--keep", "10%", "--weighting", "0.7"]),
]


@pytest.mark.parametrize("options,args", TARGETS, ids=[" ".join(a) for _, a in TARGETS])
def test_lines_with_points_match_the_command_line(borders, places, run_cli, tmp_path, options, args):
    ours = toposimp.simplify(borders, points=places, **options)
    theirs = cli_result(run_cli, tmp_path, DATA / "nh_borders.gpkg", "borders", *args,
                        points=f"{DATA / 'nh_borders.gpkg'}:places")
    assert wkb_list(ours.geometry) == wkb_list(theirs.geometry)
    assert toposimp.summary(ours)["vertices_out"] < toposimp.summary(ours)["vertices_in"]


@pytest.mark.parametrize("options,args", [({"keep": 0.1}, ["--keep", "10%"]), ({"max": True}, ["--max"]),
                                          ({"keep": 0.3, "decimals": 2}, ["--keep", "30%", "--decimals", "2"]),
                                          ({"keep": 0.1, "spherical": True}, ["--keep", "10%", "--spherical"])])
def test_polygons_match_the_command_line(states, run_cli, tmp_path, options, args):
    ours = toposimp.simplify(states, **options)
    theirs = cli_result(run_cli, tmp_path, DATA / "ne_states_slice.gpkg", "states", *args)
    assert wkb_list(ours.geometry) == wkb_list(theirs.geometry)


def test_levels_match_the_command_line_and_nest(states, run_cli, tmp_path):
    levels = toposimp.simplify(states, levels=["50%", "30%", 900])
    assert len(levels) == 3
    run_cli("map", DATA / "ne_states_slice.gpkg", "--levels", "50%,30%,900", "-o", tmp_path / "s_{level}.gpkg")
    for level, name in zip(levels, ["50pct", "30pct", "900"]):
        theirs = geopandas.read_file(tmp_path / f"s_{name}.gpkg")
        assert wkb_list(level.geometry) == wkb_list(theirs.geometry)
    counts = [toposimp.summary(level)["vertices_out"] for level in levels]
    assert counts[0] > counts[1] > counts[2]
    coarse = {tuple(c) for g in levels[2].geometry for p in g.geoms for c in p.exterior.coords}
    fine = {tuple(c) for g in levels[1].geometry for p in g.geoms for c in p.exterior.coords}
    assert coarse <= fine


def test_round_trip_keeps_index_columns_dtypes_crs_and_untouched_geometries(borders):
    data = borders.copy()
    data.index = pandas.Index([f"line{k}" for k in range(len(data))], name="key")
    data["weight"] = numpy.arange(len(data), dtype="float32")
    data["flag"] = pandas.array([k % 2 == 0 for k in range(len(data))], dtype="boolean")
    data = with_geometries(data, {3: None, 5: shapely.geometry.LineString(),
                                  7: shapely.geometry.MultiLineString([data.geometry.iloc[8].coords, data.geometry.iloc[9].coords])})
    before = data.copy()
    out = toposimp.simplify(data, keep=0.2)
    assert type(out) is geopandas.GeoDataFrame
    assert out.index.equals(data.index) and out.index.name == "key"
    assert list(out.columns) == list(data.columns)
    assert out.dtypes.equals(data.dtypes)
    assert out.crs == data.crs
    assert out.geometry.name == data.geometry.name
    assert out.loc["line3", "geometry"] is None
    assert out.loc["line5", "geometry"].is_empty
    assert list(out.geom_type.fillna("None")) == list(data.geom_type.fillna("None"))
    pandas.testing.assert_frame_equal(out.drop(columns="geometry"), data.drop(columns="geometry"))
    # The input is left as it was.
    assert wkb_list(data.geometry) == wkb_list(before.geometry)
    assert "toposimp" not in data.attrs and "toposimp" in out.attrs
    assert out.geometry.values[0].wkb != data.geometry.values[0].wkb or len(data.geometry.values[0].coords) <= 2


def test_geoseries_in_geoseries_out(borders):
    series = borders.geometry.copy()
    series.index = series.index + 100
    out = toposimp.simplify(series, keep=0.1)
    assert type(out) is geopandas.GeoSeries
    assert out.index.equals(series.index) and out.crs == series.crs


def test_layers_together_share_their_borders(states):
    west = states[states.geometry.centroid.x < 11]
    east = states[states.geometry.centroid.x >= 11]
    together = toposimp.simplify({"west": west, "east": east}, keep=0.1)
    assert set(together) == {"west", "east"}
    alone = toposimp.simplify(states, keep=0.1)
    combined = pandas.concat([together["west"], together["east"]]).loc[states.index]
    assert wkb_list(combined.geometry) == wkb_list(alone.geometry)
    as_list = toposimp.simplify([west, east], keep=0.1)
    assert wkb_list(as_list[0].geometry) == wkb_list(together["west"].geometry)


def test_threads_give_the_same_result(states, borders, places):
    for data, points in ((states, None), (borders, places)):
        one = toposimp.simplify(data, keep=0.05, points=points, threads=1)
        two = toposimp.simplify(data, keep=0.05, points=points, threads=2)
        assert wkb_list(one.geometry) == wkb_list(two.geometry)
        assert toposimp.summary(two)["parallel"]["threads"] == 2


def test_per_feature_simplify_breaks_what_toposimp_keeps(states):
    ours = toposimp.simplify(states, keep=0.05)
    target = toposimp.summary(ours)["vertices_out"]
    naive = states.copy()
    naive["geometry"] = states.geometry.simplify(0.05, preserve_topology=True)
    assert toposimp.check(states, ours).empty
    broken = toposimp.check(states, naive)
    assert len(broken) > 0
    assert set(broken.columns) == {"kind", "layer", "feature", "other", "x", "y", "detail", "decided_by", "index", "other_index"}
    crossing = broken[broken["kind"] == "new_crossing"].iloc[0]
    assert crossing["index"] == states.index[int(crossing["feature"])]
    assert crossing["other_index"] == states.index[int(crossing["other"])]
    assert "border_no_longer_shared" in set(broken["kind"])
    assert target > 0


def test_check_sees_a_point_on_the_wrong_side(borders, places):
    line = geopandas.GeoSeries([shapely.geometry.LineString([(0, 0), (1, 1), (2, 0)])])
    point = geopandas.GeoSeries([shapely.geometry.Point(1, 0.5)])
    chord = geopandas.GeoSeries([shapely.geometry.LineString([(0, 0), (2, 0)])])
    report = toposimp.check(line, chord, points=point)
    assert list(report["kind"]) == ["point_changed_side"]
    assert list(report["index"]) == [0]
    labelled = toposimp.check(line.set_axis(["bent"]), chord.set_axis(["bent"]), points=point)
    assert list(labelled["index"]) == ["bent"]
    assert report.attrs["toposimp"]["control_points"] == 1
    # toposimp keeps the vertex: removing it would put the point on the other side.
    kept = toposimp.simplify(line, max=True, points=point)
    assert kept.values[0].wkb == line.values[0].wkb
    assert toposimp.check(line, kept, points=point).empty
    assert toposimp.check(borders, toposimp.simplify(borders, keep=0.1, points=places), points=places).empty


def test_bad_input_raises_with_the_layer_and_feature(borders):
    data = with_geometries(borders, {4: shapely.geometry.GeometryCollection([shapely.geometry.Point(0, 0)])})
    with pytest.raises(toposimp.InputError, match=r"layer '0', feature 4: geometry is Geometry Collection"):
        toposimp.simplify(data)
    nan = with_geometries(borders, {2: shapely.geometry.LineString([(0, 0), (float("nan"), 1), (2, 2)])})
    with pytest.raises(toposimp.InputError, match="feature 2"):
        toposimp.simplify(nan)
    points_only = geopandas.GeoSeries([shapely.geometry.Point(0, 0)])
    with pytest.raises(toposimp.InputError, match="no line or polygon geometry"):
        toposimp.simplify(points_only)


def test_bad_options_raise_usage_errors(borders, states):
    with pytest.raises(toposimp.UsageError, match="one target"):
        toposimp.simplify(borders, keep=0.1, max=True)
    with pytest.raises(toposimp.UsageError, match="more than all vertices"):
        toposimp.simplify(borders, keep="200%")
    with pytest.raises(ValueError):  # UsageError is a ValueError
        toposimp.simplify(borders, keep=-1)
    with pytest.raises(toposimp.UsageError, match="precision"):
        toposimp.simplify(borders, precision="fine")
    with pytest.raises(toposimp.InputError, match="not in a geographic CRS"):
        toposimp.simplify(borders, spherical=True)
    with pytest.raises(TypeError):
        toposimp.simplify(states.drop(columns="geometry"))


def test_unreached_target_is_a_warning(borders):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        out = toposimp.simplify(borders, keep_points=0)
    assert any(issubclass(w.category, toposimp.ToposimpWarning) and "target not reached" in str(w.message) for w in caught)
    assert not toposimp.summary(out)["target"]["reached"]


def test_progress_is_reported_and_can_stop_the_run(states):
    seen = []
    toposimp.simplify(states, keep=0.1, progress=lambda phase, done: seen.append((phase, done)))
    phases = [phase for phase, _ in seen]
    assert "simplifying" in phases and any(p.startswith("reading") for p in phases)
    assert all(0 <= done <= 1 for _, done in seen)

    class Stop(Exception):
        pass

    def stop(phase, done):
        if phase == "simplifying":
            raise Stop()
    with pytest.raises(Stop):
        toposimp.simplify(states, keep=0.1, progress=stop)


def test_ctrl_c_interrupts_the_engine(states):
    def interrupt(phase, done):
        if phase == "simplifying":
            os.kill(os.getpid(), signal.SIGINT)
    with pytest.raises(KeyboardInterrupt):
        toposimp.simplify(states, keep=0.1, progress=interrupt)
    # Python's own handler is back afterwards.
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler


def test_summary_is_the_command_lines(states, run_cli, tmp_path):
    ours = toposimp.summary(toposimp.simplify(states, keep=0.1))
    theirs = json.loads(run_cli("map", DATA / "ne_states_slice.gpkg", "--keep", "10%", "--json", "-o",
                                tmp_path / "s.gpkg").stdout)
    for key in ("features", "vertices_in", "vertices_out", "removed", "blocked", "target", "pinned_by_crossing"):
        assert ours[key] == theirs[key], key


def test_wkb_round_trip_is_bit_exact():
    # Coordinates no decimal text holds shortly: the doubles must come back as they went.
    xs = numpy.nextafter(numpy.linspace(0.1, 0.9, 40), 1.0)
    line = shapely.geometry.LineString([(x, (x * 7.3) % 1.0 + 1e-13) for x in xs])
    out = toposimp.simplify(geopandas.GeoSeries([line]), keep=1.0)
    assert out.values[0].wkb == line.wkb


def test_wkb_path_gives_what_the_geos_path_gives(states, borders, places, monkeypatch):
    # Debian's shapely shares the extension's GEOS, so geometries go through it; any other shapely
    # sends WKB. Both must give the same result, errors included.
    assert toposimp._shares_geos()
    through_geos = [toposimp.simplify(states, keep=0.3), toposimp.simplify(borders, keep=0.1, points=places)]
    monkeypatch.setattr(toposimp, "_shared_geos", False)
    through_wkb = [toposimp.simplify(states, keep=0.3), toposimp.simplify(borders, keep=0.1, points=places)]
    for a, b in zip(through_geos, through_wkb):
        assert wkb_list(a.geometry) == wkb_list(b.geometry)
    assert toposimp.check(borders, through_wkb[1], points=places).empty
    lines = geopandas.GeoSeries([shapely.geometry.LineString([(0, 0), (1, 1)])])
    with pytest.raises(toposimp.InputError, match="feature 0: control points must be Point or MultiPoint"):
        toposimp.simplify(lines, points=lines)
    monkeypatch.setattr(toposimp, "_shared_geos", True)
    with pytest.raises(toposimp.InputError, match="feature 0: control points must be Point or MultiPoint"):
        toposimp.simplify(lines, points=lines)


def test_the_engine_runs_without_the_gil():
    # 240 random walks of 1 000 vertices: the call is mostly the engine, and another Python thread
    # counts through it only if the engine has let the GIL go (no progress callback: a callback
    # takes the GIL, and Python may hand it to the other thread then).
    import threading
    import time
    rng = numpy.random.default_rng(3)
    walks = [shapely.geometry.LineString(numpy.cumsum(rng.normal(size=(1000, 2)), axis=0) + 40 * k) for k in range(240)]
    series = geopandas.GeoSeries(walks)
    counter, stop = [0], threading.Event()

    def count():
        while not stop.is_set():
            counter[0] += 1
    worker = threading.Thread(target=count)
    worker.start()
    try:
        time.sleep(0.2)
        start_count, start = counter[0], time.perf_counter()
        time.sleep(0.2)
        rate = (counter[0] - start_count) / (time.perf_counter() - start)  # alone
        before, start = counter[0], time.perf_counter()
        out = toposimp.simplify(series, keep=0.05, threads=1)
        during, seconds = counter[0] - before, time.perf_counter() - start
    finally:
        stop.set()
        worker.join()
    engine = toposimp.summary(out)["seconds"]["simplify"]
    # Held through the engine, the GIL would let the other thread count only in the call's Python
    # parts (measured: 2-4 % of the engine's time's worth); let go, it counts through the engine
    # too (measured: 50-100 %, less when other tests share the cores).
    assert during > 0.1 * rate * engine, (during, rate, engine, seconds)


def test_ctrl_c_stops_a_long_run_at_once(tmp_path):
    # A separate Python runs a long simplification (2 M vertices: 4 s of engine in a debug build
    # here); SIGINT half a second in must end it soon with KeyboardInterrupt (measured: 0.4 s in a
    # debug build), not when the engine is done (3.5 s later).
    import subprocess
    import sys
    import time
    script = tmp_path / "long.py"
    script.write_text(
        "import sys, numpy, geopandas, shapely.geometry, toposimp\n"
        "rng = numpy.random.default_rng(5)\n"
        "walks = [shapely.geometry.LineString(numpy.cumsum(rng.normal(size=(1000, 2)), axis=0) + 40 * k) for k in range(2000)]\n"
        "series = geopandas.GeoSeries(walks)\n"
        "print('go', flush=True)\n"
        "out = toposimp.simplify(series, keep=0.01, threads=1)\n"
        "print('finished', toposimp.summary(out)['seconds']['simplify'], flush=True)\n")
    process = subprocess.Popen([sys.executable, str(script)], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    assert process.stdout.readline().strip() == "go"
    time.sleep(0.5)
    sent = time.perf_counter()
    process.send_signal(signal.SIGINT)
    _, err = process.communicate(timeout=60)
    waited = time.perf_counter() - sent
    assert "KeyboardInterrupt" in err
    assert waited < 2.0, waited

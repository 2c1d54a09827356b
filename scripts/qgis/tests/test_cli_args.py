"""Parameter values -> toposimp arguments, without QGIS.

Each mapping is also run through the real executable's parser (`--help` appended is not enough:
it stops parsing), by running the command for real on the small samples in testdata/ when
TOPOSIMP_BINARY is set (ctest sets it)."""

import json
import os
import subprocess
import sys
import tempfile
import unittest

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))

from toposimp_processing import cli_args  # noqa: E402
from toposimp_processing.cli_args import ArgumentError  # noqa: E402

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", "..", ".."))
TESTDATA = os.path.join(ROOT, "testdata")
BINARY = os.environ.get("TOPOSIMP_BINARY")


class MapArgs(unittest.TestCase):
    def test_defaults_keep_ten_percent_with_progress_and_json(self):
        self.assertEqual(cli_args.map_args("in.gpkg", "out.gpkg"),
                         ["map", "in.gpkg", "-o", "out.gpkg", "--keep", "10%", "--overwrite", "--progress", "--json"])

    def test_every_target(self):
        def target_of(index, **values):
            args = cli_args.map_args("in.shp", "out.shp", target=index, **values)
            return args[4:args.index("--overwrite")]
        self.assertEqual(target_of(0, percent=2.5), ["--keep", "2.5%"])
        self.assertEqual(target_of(0, percent=100), ["--keep", "100%"])
        self.assertEqual(target_of(1, count=500), ["--keep-points", "500"])
        self.assertEqual(target_of(2, count=0), ["--remove-points", "0"])
        self.assertEqual(target_of(3, area=0.125), ["--max-area", "0.125"])
        self.assertEqual(target_of(3, area=1e-300), ["--max-area", "1e-300"])
        self.assertEqual(target_of(4), ["--max"])

    def test_numbers_keep_their_exact_value(self):
        # repr() is the shortest text that reads back as the same double.
        args = cli_args.map_args("a", "b", target=3, area=0.1 + 0.2)
        self.assertEqual(float(args[args.index("--max-area") + 1]), 0.1 + 0.2)

    def test_layers_points_and_options(self):
        args = cli_args.map_args("in.gpkg", "out.gpkg", input_layer="roads", output_layer="roads_10",
                                 points_path="places.gpkg", points_layer="cities", arithmetic=1,
                                 validate=True, threads=2)
        self.assertEqual(args, ["map", "in.gpkg", "-o", "out.gpkg", "-l", "roads", "--nln", "roads_10",
                                "--points", "places.gpkg:cities", "--keep", "10%", "--arithmetic", "rational",
                                "--validate", "--overwrite", "-j", "2", "--progress", "--json"])
        self.assertIn("--points", cli_args.map_args("a", "b", points_path="p.shp"))
        self.assertEqual(cli_args.map_args("a", "b", points_path="p.shp")[5], "p.shp")

    def test_rounding_and_ranking(self):
        def options_of(**values):
            args = cli_args.map_args("in.gpkg", "out.gpkg", **values)
            return args[6:args.index("--overwrite")]
        self.assertEqual(options_of(decimals=4), ["--decimals", "4"])
        self.assertEqual(options_of(precision=0.25), ["--precision", "0.25"])
        self.assertEqual(options_of(weighting=0.7, spherical=True), ["--weighting", "0.7", "--spherical"])
        self.assertEqual(options_of(decimals=0, weighting=0), ["--decimals", "0", "--weighting", "0"])

    def test_bad_values_are_refused_with_a_message(self):
        cases = [dict(percent=101), dict(percent=-1), dict(target=1), dict(target=1, count=2.5),
                 dict(target=2, count=-3), dict(target=3, area=-1), dict(target=5), dict(arithmetic=3),
                 dict(percent=float("nan")), dict(threads=-1), dict(decimals=3, precision=0.1),
                 dict(decimals=-1), dict(decimals=2.5), dict(decimals=16), dict(precision=0),
                 dict(weighting=1.5), dict(weighting=-0.1)]
        for values in cases:
            with self.subTest(values=values), self.assertRaises(ArgumentError) as raised:
                cli_args.map_args("a", "b", **values)
            self.assertTrue(str(raised.exception))
        with self.assertRaises(ArgumentError):
            cli_args.map_args("", "b")


class CheckAndMeshArgs(unittest.TestCase):
    def test_check(self):
        self.assertEqual(cli_args.check_args("a.gpkg", "b.shp", layer="roads", simplified_layer="b",
                                             points_path="p.gpkg", points_layer="cities", key_field="id",
                                             errors_path="e.geojson"),
                         ["check", "a.gpkg", "b.shp", "-l", "roads", "--simplified-layer", "b",
                          "--points", "p.gpkg:cities", "--key", "id", "--geojson-errors", "e.geojson",
                          "--progress", "--json"])
        with self.assertRaises(ArgumentError):
            cli_args.check_args("a.gpkg", None)

    def test_mesh_targets_and_flags(self):
        self.assertEqual(cli_args.mesh_args("m.ply", "o.obj"),
                         ["mesh", "m.ply", "-o", "o.obj", "--keep", "10%", "--overwrite", "--progress", "--json"])
        self.assertEqual(cli_args.mesh_args("m.ply", "o.obj", target=1, count=5000)[4:6], ["--keep-faces", "5000"])
        self.assertEqual(cli_args.mesh_args("m.ply", "o.obj", target=2, max_error=0.5)[4:6], ["--max-error", "0.5"])
        args = cli_args.mesh_args("dem.tif", "tin.gpkg", band=2, free_boundary=True, output_layer="tin_5",
                                  hausdorff=False, threads=1, terrain=True, triangulate=True, weld=True)
        for expected in (["--band", "2"], ["--free-boundary"], ["--nln", "tin_5"], ["--no-hausdorff"],
                         ["-j", "1"], ["--terrain"], ["--triangulate"], ["--weld"]):
            position = args.index(expected[0])
            self.assertEqual(args[position:position + len(expected)], expected)
        for values in (dict(target=1), dict(target=2), dict(target=2, max_error=-1), dict(target=3),
                       dict(lock_boundary=True, free_boundary=True), dict(percent=150)):
            with self.subTest(values=values), self.assertRaises(ArgumentError):
                cli_args.mesh_args("m.ply", "o.ply", **values)


class Destinations(unittest.TestCase):
    def test_forms_qgis_gives(self):
        split = cli_args.split_destination
        self.assertEqual(split("/tmp/out.gpkg"), ("/tmp/out.gpkg", None))
        self.assertEqual(split("/tmp/out.gpkg|layername=roads"), ("/tmp/out.gpkg", "roads"))
        self.assertEqual(split("ogr:dbname='/data/my maps.gpkg' table=\"roads 10\" (geom)"),
                         ("/data/my maps.gpkg", "roads 10"))
        self.assertEqual(split("ogr:dbname='/d/a.gpkg' table=\"t\""), ("/d/a.gpkg", "t"))
        with self.assertRaises(ArgumentError):
            split("")


@unittest.skipUnless(BINARY, "TOPOSIMP_BINARY not set (ctest sets it to the built executable)")
class ArgumentsTheExecutableAccepts(unittest.TestCase):
    """Every mapping above, run for real on the samples: the executable accepts the arguments
    and does what they say."""

    def run_tool(self, args):
        done = subprocess.run([BINARY] + args, capture_output=True, text=True)
        self.assertIn(done.returncode, (0, 1), done.stderr)
        return json.loads(done.stdout.strip().splitlines()[-1]), done.stderr

    def test_map_targets(self):
        gpkg = os.path.join(TESTDATA, "nh_borders.gpkg")
        with tempfile.TemporaryDirectory() as tmp:
            out = os.path.join(tmp, "out.gpkg")
            cases = [(dict(target=0, percent=20), lambda s: s["target"]["reached"] and abs(s["vertices_out"] - 0.2 * s["vertices_in"]) < 1),
                     (dict(target=1, count=300), lambda s: s["vertices_out"] == 300),
                     (dict(target=2, count=100), lambda s: s["removed"] == 100),
                     (dict(target=3, area=1e-6), lambda s: "effective area" in s["target"]["criterion"]),
                     (dict(target=4), lambda s: s["target"]["criterion"] == "max")]
            for values, holds in cases:
                with self.subTest(values=values):
                    summary, _ = self.run_tool(cli_args.map_args(
                        gpkg, out, input_layer="borders", points_path=gpkg, points_layer="places", threads=1,
                        **values))
                    self.assertTrue(holds(summary), summary)
                    self.assertEqual(summary["control_points"], 26)
            # Rounded and ranked: every coordinate written on the 0.001 grid, the run clean.
            summary, _ = self.run_tool(cli_args.map_args(gpkg, out, input_layer="borders", points_path=gpkg,
                                                         points_layer="places", decimals=3, weighting=0.7,
                                                         validate=True))
            self.assertEqual(summary["rounding"]["grid"], "0.001")
            self.assertEqual(summary["ranking"]["weighting"], 0.7)
            states = os.path.join(TESTDATA, "ne_states_slice.gpkg")
            summary, _ = self.run_tool(cli_args.map_args(states, out, spherical=True, precision=0.05))
            self.assertTrue(summary["ranking"]["spherical"], summary)
            self.assertEqual(summary["rounding"]["grid"], "0.05")
            summary, stderr = self.run_tool(cli_args.map_args(gpkg, out, input_layer="borders", validate=True,
                                                              points_path=gpkg, points_layer="places",
                                                              arithmetic=1, output_layer="renamed"))
            self.assertEqual(summary["arithmetic"], "rational")
            self.assertIn("PROGRESS 0 validating", stderr)
            report, _ = self.run_tool(cli_args.check_args(gpkg, out, layer="borders", simplified_layer="renamed",
                                                          points_path=gpkg, points_layer="places",
                                                          errors_path=os.path.join(tmp, "e.geojson")))
            self.assertTrue(report["clean"], report)
            self.assertTrue(os.path.exists(os.path.join(tmp, "e.geojson")))

    def test_mesh_targets(self):
        torus = os.path.join(TESTDATA, "mesh", "torus.off")
        with tempfile.TemporaryDirectory() as tmp:
            out = os.path.join(tmp, "t.ply")
            summary, _ = self.run_tool(cli_args.mesh_args(torus, out, target=1, count=1000, hausdorff=False))
            self.assertEqual(summary["faces_out"], 1000)
            self.assertNotIn("hausdorff", summary)
            summary, _ = self.run_tool(cli_args.mesh_args(torus, out, target=2, max_error=1e-4))
            self.assertLessEqual(summary["max_quadric_error"], 1e-4)
            self.assertIn("hausdorff", summary)
            hills = os.path.join(TESTDATA, "mesh", "hills.obj")
            summary, _ = self.run_tool(cli_args.mesh_args(hills, out, terrain=True, lock_boundary=True, percent=5))
            self.assertTrue(summary["terrain"] and summary["lock_boundary"], summary)


if __name__ == "__main__":
    unittest.main()

#!/usr/bin/env python3
"""The provider in a real QGIS, headless: qgis_process (Debian package `qgis`) loads the plugin
from scripts/qgis (or TOPOSIMP_QGIS_PLUGINS), runs each algorithm on the samples in testdata/,
and the results are checked independently (toposimp check, ogrinfo).

Exit 77 (ctest: skipped) with the reason when qgis_process is not installed."""

import json
import math
import os
import shutil
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.abspath(os.path.join(HERE, "..", "..", ".."))
TESTDATA = os.path.join(ROOT, "testdata")
SKIP = 77


def fail(message):
    print("FAIL: " + message)
    sys.exit(1)


def qgis_process_command():
    # Debian's /usr/bin/qgis_process wrapper passes --noversioncheck, which the 3.22 binary
    # rejects ("Command --noversioncheck not known!"); the binary itself works.
    for name in ("qgis_process.bin", "qgis_process"):
        found = shutil.which(name)
        if found:
            return found
    return None


class Qgis:
    def __init__(self, executable, home, plugins, toposimp_dir):
        self.executable = executable
        self.toposimp_dir = toposimp_dir
        runtime = os.path.join(home, "runtime")
        os.makedirs(runtime, mode=0o700)
        # PATH: the toposimp under test, then the system's. QGIS's embedded Python finds its
        # standard library from the first `python3` on PATH, so another one (pyenv, a venv)
        # before /usr/bin would break `import qgis`.
        system_path = os.pathsep.join(["/usr/local/bin", "/usr/bin", "/bin"])
        self.env = {key: value for key, value in os.environ.items()
                    if not key.startswith(("PYENV", "PYTHONHOME", "PYTHONPATH", "VIRTUAL_ENV", "XDG_"))}
        self.env.update(HOME=home, QT_QPA_PLATFORM="offscreen", QGIS_PLUGINPATH=plugins, XDG_RUNTIME_DIR=runtime,
                        PATH=toposimp_dir + os.pathsep + system_path,
                        PYTHONDONTWRITEBYTECODE="1")  # no __pycache__ in the plugin folder under test

    def without_toposimp_on_path(self, configured=None):
        """The same QGIS with toposimp off PATH and, if given, its path in the provider's setting
        (what Settings > Options > Processing > Providers > toposimp writes)."""
        self.env["PATH"] = os.pathsep.join(d for d in self.env["PATH"].split(os.pathsep) if d != self.toposimp_dir)
        ini = os.path.join(self.env["HOME"], ".local", "share", "QGIS", "QGIS3", "profiles", "default", "QGIS", "QGIS3.ini")
        with open(ini) as settings:
            text = settings.read().split("\n[Processing]\n")[0]  # the section this method appends
        with open(ini, "w") as settings:
            settings.write(text + "\n[Processing]\nConfiguration\\TOPOSIMP_EXECUTABLE={}\n".format(configured or ""))

    def call(self, *args):
        return subprocess.run([self.executable] + list(args), env=self.env, capture_output=True, text=True,
                              timeout=300)

    def run(self, algorithm, **parameters):
        """Runs an algorithm; returns (exit status, results dict, all output)."""
        args = ["--json", "run", algorithm, "--"] + ["{}={}".format(k, v) for k, v in parameters.items()]
        done = self.call(*args)
        text = done.stdout + done.stderr
        results = {}
        start = done.stdout.find("{")
        if start >= 0:
            try:
                results = json.loads(done.stdout[start:]).get("results", {})
            except ValueError:
                pass
        return done.returncode, results, text


def toposimp(binary, *args):
    return subprocess.run([binary] + list(args), capture_output=True, text=True, timeout=300)


def main():
    executable = qgis_process_command()
    if not executable:
        print("SKIPPED: qgis_process not found; install the Debian package qgis (scripts/setup.sh --qgis) to run this test")
        return SKIP
    binary = os.environ.get("TOPOSIMP_BINARY") or shutil.which("toposimp")
    if not binary:
        fail("no toposimp executable (set TOPOSIMP_BINARY)")
    plugins = os.environ.get("TOPOSIMP_QGIS_PLUGINS", os.path.join(ROOT, "scripts", "qgis"))
    with tempfile.TemporaryDirectory() as tmp:
        home = os.path.join(tmp, "home")
        os.makedirs(home)
        qgis = Qgis(executable, home, plugins, os.path.dirname(os.path.abspath(binary)))

        enabled = qgis.call("plugins", "enable", "toposimp_processing")
        if enabled.returncode != 0:
            fail("plugins enable toposimp_processing: " + enabled.stdout + enabled.stderr)
        listing = qgis.call("list").stdout
        for algorithm in ("toposimp:map", "toposimp:check", "toposimp:mesh", "toposimp:dem"):
            if algorithm not in listing:
                fail(algorithm + " not listed by qgis_process:\n" + listing)

        # map: the borders of the sample with its places as control points, to 20 %.
        gpkg = os.path.join(TESTDATA, "nh_borders.gpkg")
        out = os.path.join(tmp, "borders_20.gpkg")
        code, results, text = qgis.run("toposimp:map", INPUT=gpkg + "|layername=borders",
                                       POINTS=gpkg + "|layername=places", PERCENT=20, OUTPUT=out)
        if code != 0 or not os.path.exists(out):
            fail("toposimp:map: exit {}\n{}".format(code, text))
        if not (results.get("VERTICES_IN") == 992 and abs(results.get("VERTICES_OUT", 0) - 0.2 * 992) < 1):
            fail("toposimp:map results: {}".format(results))
        checked = toposimp(binary, "check", gpkg, out, "-l", "borders", "--points", gpkg + ":places", "--json")
        report = json.loads(checked.stdout)
        if checked.returncode != 0 or not report["clean"] or report["features"] != 27:
            fail("the map output is not a clean simplification: " + checked.stdout + checked.stderr)

        # map rounded to 3 decimals with weighted ranking: clean on the grid.
        rounded = os.path.join(tmp, "borders_rounded.gpkg")
        code, results, text = qgis.run("toposimp:map", INPUT=gpkg + "|layername=borders",
                                       POINTS=gpkg + "|layername=places", PERCENT=20, DECIMALS=3, WEIGHTING=0.7,
                                       OUTPUT=rounded)
        if code != 0 or not os.path.exists(rounded):
            fail("toposimp:map with DECIMALS: exit {}\n{}".format(code, text))
        checked = toposimp(binary, "check", gpkg, rounded, "-l", "borders", "--points", gpkg + ":places",
                           "--decimals", "3", "--json")
        if checked.returncode != 0 or not json.loads(checked.stdout)["clean"]:
            fail("the rounded map output is not clean on its grid: " + checked.stdout + checked.stderr)
        from osgeo import ogr  # (QGIS depends on GDAL's Python bindings)

        def points(geometry):
            if geometry.GetGeometryCount() == 0:
                return geometry.GetPoints() or []
            return [p for k in range(geometry.GetGeometryCount()) for p in points(geometry.GetGeometryRef(k))]
        source = ogr.Open(rounded)  # (held: its layer and features die with it)
        off = []
        for feature in source.GetLayer(0):
            off += [(x, y) for x, y in points(feature.GetGeometryRef())[:] if
                    abs(x * 1000 - round(x * 1000)) > 1e-6 or abs(y * 1000 - round(y * 1000)) > 1e-6]
        if off:
            fail("toposimp:map with DECIMALS=3 wrote coordinates off the grid, e.g. {}".format(off[:3]))

        # check, through QGIS, with the violations layer written.
        errors = os.path.join(tmp, "violations.geojson")
        code, results, text = qgis.run("toposimp:check", ORIGINAL=gpkg + "|layername=borders", SIMPLIFIED=out,
                                       POINTS=gpkg + "|layername=places", ERRORS=errors)
        if code != 0 or results.get("CLEAN") is not True or results.get("VIOLATIONS") != 0:
            fail("toposimp:check: exit {} results {}\n{}".format(code, results, text))
        if not os.path.exists(errors):
            fail("toposimp:check wrote no violations layer")

        # mesh: the torus to 10 % of its faces, in the plain output form, which shows the
        # progress phases as the provider reported them.
        torus_out = os.path.join(tmp, "torus.ply")
        done = qgis.call("run", "toposimp:mesh", "--", "INPUT=" + os.path.join(TESTDATA, "mesh", "torus.off"),
                         "OUTPUT=" + torus_out)
        text = done.stdout + done.stderr
        if done.returncode != 0 or "FACES_IN:\t4800" not in text or "FACES_OUT:\t480\n" not in text or not os.path.exists(torus_out):
            fail("toposimp:mesh: exit {}\n{}".format(done.returncode, text))
        for phase in ("reading", "simplifying", "writing", "measuring the Hausdorff distance"):
            if phase not in text:
                fail("progress phase '{}' not reported:\n{}".format(phase, text))

        # dem: a GeoTIFF in UTM 33N with a hole of nodata -> a TIN layer in the same CRS.
        asc, tif = os.path.join(tmp, "dem.asc"), os.path.join(tmp, "dem.tif")
        n = 40
        with open(asc, "w") as grid:
            grid.write("ncols {0}\nnrows {0}\nxllcorner 500000\nyllcorner 5000000\ncellsize 10\nNODATA_value -9999\n".format(n))
            for r in range(n):
                grid.write(" ".join("-9999" if (r - 20) ** 2 + (c - 20) ** 2 < 9
                                    else "{:.2f}".format(100 + 20 * math.sin(r * 0.2) * math.cos(c * 0.15))
                                    for c in range(n)) + "\n")
        translated = subprocess.run(["gdal_translate", "-q", "-a_srs", "EPSG:32633", asc, tif], capture_output=True, text=True)
        if translated.returncode != 0:
            fail("gdal_translate: " + translated.stderr)
        tin = os.path.join(tmp, "tin.gpkg")
        code, results, text = qgis.run("toposimp:dem", INPUT=tif, PERCENT=10, OUTPUT=tin)
        if code != 0 or not results.get("FACES_OUT"):
            fail("toposimp:dem: exit {} results {}\n{}".format(code, results, text))
        info = subprocess.run(["ogrinfo", "-so", "-al", tin], capture_output=True, text=True).stdout
        if ("3D Polygon" not in info or "Feature Count: {}".format(results["FACES_OUT"]) not in info
                or 'ID["EPSG",32633]' not in info):
            fail("the TIN layer is not what was asked:\n" + info)

        # A CLI error reaches QGIS as a Processing error with the CLI's own message.
        code, results, text = qgis.run("toposimp:map", INPUT=gpkg + "|layername=borders",
                                       OUTPUT=os.path.join(tmp, "no", "such", "folder", "x.gpkg"))
        if code == 0 or "does not exist" not in text:
            fail("an output in a missing folder did not fail with toposimp's message: exit {}\n{}".format(code, text))

        # The executable's path from the provider's setting, when it is not on PATH; and a
        # clear error when it is neither.
        qgis.without_toposimp_on_path(os.path.abspath(binary))
        code, results, text = qgis.run("toposimp:mesh", INPUT=os.path.join(TESTDATA, "mesh", "torus.off"),
                                       OUTPUT=os.path.join(tmp, "configured.obj"))
        if code != 0 or results.get("FACES_OUT") != 480:
            fail("toposimp:mesh with the executable set in the settings: exit {}\n{}".format(code, text))
        qgis.without_toposimp_on_path(None)
        code, results, text = qgis.run("toposimp:mesh", INPUT=os.path.join(TESTDATA, "mesh", "torus.off"),
                                       OUTPUT=os.path.join(tmp, "nowhere.obj"))
        if code == 0 or "toposimp was not found on PATH" not in text:
            fail("no executable anywhere did not give the 'not found' error: exit {}\n{}".format(code, text))
        # The Python package inside QGIS's own Python (what its console runs), with the plugin's
        # folder among QGIS's plugin paths: a Processing script that imports toposimp and
        # simplifies the sample with it. TOPOSIMP_PYTHONPATH: where the package under test is.
        package = os.environ.get("TOPOSIMP_PYTHONPATH")
        if package:
            scripts = os.path.join(home, ".local", "share", "QGIS", "QGIS3", "profiles", "default", "processing", "scripts")
            os.makedirs(scripts, exist_ok=True)
            shutil.copy(os.path.join(HERE, "scripts", "toposimp_import.py"), scripts)
            qgis.env.update(PYTHONPATH=package, TOPOSIMP_TESTDATA=TESTDATA)
            code, results, text = qgis.run("script:toposimp_import")
            if code != 0 or results.get("VERTICES_OUT") != 100 or not str(results.get("MODULE", "")).startswith(package):
                fail("import toposimp in QGIS's Python: exit {}\n{}".format(code, text))
    print("qgis_process: map, check, mesh, dem, the executable setting and errors, and import toposimp in QGIS's "
          "Python all behaved" if package else "qgis_process: map, check, mesh, dem, the executable setting and errors "
          "all behaved (TOPOSIMP_PYTHONPATH unset: the Python package was not tried)")
    return 0


if __name__ == "__main__":
    sys.exit(main())

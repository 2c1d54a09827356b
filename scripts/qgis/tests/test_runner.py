"""The runner without QGIS: progress, messages, errors and cancellation, with a stand-in for
QgsProcessingFeedback, against stand-in executables and (when TOPOSIMP_BINARY is set) the real one."""

import math
import os
import stat
import sys
import tempfile
import textwrap
import threading
import unittest

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))

from toposimp_processing import runner  # noqa: E402

BINARY = os.environ.get("TOPOSIMP_BINARY")


class Feedback:
    """Records what QgsProcessingFeedback would be told; cancels when `cancel_when` says so."""

    def __init__(self, cancel_when=None):
        self.progress, self.texts, self.infos, self.warnings, self.errors = [], [], [], [], []
        self.cancel_when = cancel_when
        self.lock = threading.Lock()

    def isCanceled(self):  # noqa: N802
        with self.lock:
            return bool(self.cancel_when and self.cancel_when(self))

    def setProgress(self, value):  # noqa: N802
        with self.lock:
            self.progress.append(value)

    def setProgressText(self, text):  # noqa: N802
        with self.lock:
            self.texts.append(text)

    def pushInfo(self, text):  # noqa: N802
        self.infos.append(text)

    def pushWarning(self, text):  # noqa: N802
        self.warnings.append(text)

    def reportError(self, text, fatal=False):  # noqa: N802
        self.errors.append(text)


def fake_tool(folder, body):
    """An executable Python script with `body` (sys, os, signal, time imported)."""
    path = os.path.join(folder, "toposimp")
    with open(path, "w") as script:
        script.write("#!" + sys.executable + "\nimport os, signal, sys, time\n" + textwrap.dedent(body))
    os.chmod(path, os.stat(path).st_mode | stat.S_IXUSR)
    return path


class Runner(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.TemporaryDirectory()
        self.addCleanup(self.tmp.cleanup)

    def test_progress_messages_and_summary(self):
        tool = fake_tool(self.tmp.name, r'''
            err = sys.stderr
            for line in ["PROGRESS 0 reading in.gpkg", "PROGRESS 0 simplifying", "PROGRESS 50 simplifying",
                         "PROGRESS 100 simplifying", "toposimp: warning: 3 rings written back unchanged",
                         "PROGRESS 0 writing out.gpkg", "toposimp: info: 10 -> 5 vertices"]:
                print(line, file=err, flush=True)
            print("not json")
            print('{"command":"map","vertices_in":10,"vertices_out":5}')
        ''')
        feedback = Feedback()
        code, stdout = runner.run(tool, ["map", "in.gpkg"], feedback)
        self.assertEqual(code, 0)
        self.assertEqual(runner.parse_summary(stdout), {"command": "map", "vertices_in": 10, "vertices_out": 5})
        self.assertEqual(feedback.texts, ["reading in.gpkg", "simplifying", "writing out.gpkg"])
        self.assertEqual(feedback.progress, [0, 15, 50, 85, 85])  # phases laid end to end
        self.assertEqual(feedback.warnings, ["3 rings written back unchanged"])
        self.assertIn("toposimp: info: 10 -> 5 vertices", feedback.infos)
        self.assertTrue(feedback.infos[0].startswith("toposimp command: " + tool + " map in.gpkg"))

    def test_exit_one_is_a_result_not_an_error(self):
        tool = fake_tool(self.tmp.name, 'print(\'{"clean":false}\'); sys.exit(1)')
        self.assertEqual(runner.run(tool, ["check"], Feedback()), (1, '{"clean":false}\n'))

    def test_exit_two_raises_with_the_tools_message(self):
        tool = fake_tool(self.tmp.name, r'''
            print("PROGRESS 0 reading x", file=sys.stderr)
            print("toposimp: error: 'x.gpkg', layer 'roads', feature 7: geometry is Curve Polygon", file=sys.stderr)
            sys.exit(2)
        ''')
        feedback = Feedback()
        with self.assertRaises(runner.ToolError) as raised:
            runner.run(tool, [], feedback)
        self.assertEqual(str(raised.exception), "'x.gpkg', layer 'roads', feature 7: geometry is Curve Polygon")
        self.assertEqual(raised.exception.exit_code, 2)

    def test_a_crash_is_reported(self):
        tool = fake_tool(self.tmp.name, "os.kill(os.getpid(), signal.SIGSEGV)")
        with self.assertRaises(runner.ToolError) as raised:
            runner.run(tool, [], Feedback())
        self.assertIn("killed by signal 11", str(raised.exception))

    def test_cancel_stops_a_tool_that_ignores_sigterm(self):
        tool = fake_tool(self.tmp.name, r'''
            signal.signal(signal.SIGTERM, signal.SIG_IGN)
            print("PROGRESS 0 simplifying", file=sys.stderr, flush=True)
            time.sleep(60)
        ''')
        feedback = Feedback(cancel_when=lambda f: "simplifying" in f.texts)
        with self.assertRaises(runner.Cancelled):
            runner.run(tool, [], feedback, poll_seconds=0.01, stop_seconds=0.5)

    def test_finding_the_executable(self):
        tool = fake_tool(self.tmp.name, "")
        self.assertEqual(runner.find_executable(tool), tool)
        self.assertEqual(runner.find_executable(self.tmp.name), tool)  # a folder holding it
        self.assertEqual(runner.find_executable("", environ={"PATH": "/nonexistent:" + self.tmp.name}), tool)
        with self.assertRaises(runner.ExecutableNotFound) as raised:
            runner.find_executable("/no/such/toposimp")
        self.assertIn("/no/such/toposimp", str(raised.exception))
        with self.assertRaises(runner.ExecutableNotFound) as raised:
            runner.find_executable(None, environ={"PATH": "/nonexistent"})
        self.assertIn("PATH", str(raised.exception))

    def test_mesh_formats_come_from_the_tool(self):
        tool = fake_tool(self.tmp.name, r'''
            assert sys.argv[1:] == ["formats", "--json"], sys.argv
            print('{"mesh_formats":[{"name":"obj","title":"OBJ","extension":".obj","carries":"x","text_and_binary":false},'
                  '{"name":"ply","title":"PLY","extension":".ply","carries":"y","text_and_binary":true}]}')
        ''')
        formats = runner.mesh_formats(tool)
        self.assertEqual([f["name"] for f in formats], ["obj", "ply"])
        inputs, outputs = runner.mesh_file_filters(formats)
        self.assertEqual(inputs, "Meshes (*.obj *.ply *.OBJ *.PLY)")
        self.assertEqual(outputs, "PLY (*.ply);;OBJ (*.obj)")  # PLY first: the default keeps every attribute

    def test_mesh_formats_unknown_when_the_tool_cannot_say(self):
        tool = fake_tool(self.tmp.name, 'print("toposimp: error: no", file=sys.stderr); sys.exit(2)')
        self.assertEqual(runner.mesh_formats(tool), [])
        self.assertEqual(runner.mesh_file_filters([]), ("All files (*)", "All files (*)"))

    def test_overall_percent(self):
        self.assertEqual(runner.overall_percent("reading a.gpkg", 100), 15)
        self.assertEqual(runner.overall_percent("simplifying", 50), 50)
        self.assertEqual(runner.overall_percent("measuring the Hausdorff distance", 0), 95)
        self.assertEqual(runner.overall_percent("checking b against a", 40), 40)
        self.assertEqual(runner.overall_percent("something new", 250), 100)


@unittest.skipUnless(BINARY, "TOPOSIMP_BINARY not set (ctest sets it to the built executable)")
class RealExecutable(unittest.TestCase):
    def test_cancel_mid_run_leaves_nothing(self):
        with tempfile.TemporaryDirectory() as tmp:
            dem = os.path.join(tmp, "dem.asc")
            n = 500
            with open(dem, "w") as out:
                out.write("ncols {0}\nnrows {0}\nxllcorner 0\nyllcorner 0\ncellsize 1\nNODATA_value -9999\n".format(n))
                for r in range(n):
                    out.write(" ".join("{:.3f}".format(20 * math.sin(r * 0.05) * math.cos(c * 0.07) + (r * 31 + c * 17) % 7 * 0.1)
                                       for c in range(n)) + "\n")
            feedback = Feedback(cancel_when=lambda f: "simplifying" in f.texts)
            with self.assertRaises(runner.Cancelled):
                runner.run(BINARY, ["mesh", dem, "-o", os.path.join(tmp, "tin.ply"), "--progress", "-j", "1"],
                           feedback, poll_seconds=0.01)
            self.assertEqual(sorted(os.listdir(tmp)), ["dem.asc"])

    def test_mesh_formats_of_the_real_tool(self):
        names = [f["name"] for f in runner.mesh_formats(BINARY)]
        self.assertEqual(sorted(names), ["obj", "off", "ply", "stl"])
        inputs, outputs = runner.mesh_file_filters(runner.mesh_formats(BINARY))
        self.assertIn("*.stl", inputs)
        self.assertTrue(outputs.startswith("PLY (*.ply)"))

    def test_error_message_names_the_file(self):
        with tempfile.TemporaryDirectory() as tmp:
            bad = os.path.join(tmp, "bad.off")
            with open(bad, "w") as out:
                out.write("OFF\n3 1 0\n0 0 0\n1 0 0\nnan 1 0\n3 0 1 2\n")
            with self.assertRaises(runner.ToolError) as raised:
                runner.run(BINARY, ["mesh", bad, "-o", os.path.join(tmp, "out.ply"), "--progress"], Feedback())
            self.assertIn("bad.off", str(raised.exception))
            self.assertEqual(raised.exception.exit_code, 2)
            self.assertEqual(sorted(os.listdir(tmp)), ["bad.off"])


if __name__ == "__main__":
    unittest.main()

"""Runs the toposimp executable for a Processing algorithm.

Plain Python, no QGIS import. `feedback` is anything with QgsProcessingFeedback's methods used
here (isCanceled, setProgress, setProgressText, pushInfo, reportError; pushWarning where QGIS has
it), so the unit tests drive it with a stand-in.
"""

import json
import os
import shutil
import subprocess
import threading
import time

# Where each phase of a run lies on the overall progress bar (percent), by the phase's first word.
PHASE_SPANS = {
    "reading": (0, 15),
    "simplifying": (15, 85),
    "writing": (85, 95),
    "validating": (95, 100),
    "measuring": (95, 100),
    "checking": (0, 100),
}


class ToolError(Exception):
    """toposimp failed (exit status 2 or a crash); the message is what it said on stderr."""

    def __init__(self, message, exit_code):
        super().__init__(message)
        self.exit_code = exit_code


class Cancelled(Exception):
    """The user cancelled; the process was stopped and left nothing behind."""


class ExecutableNotFound(Exception):
    pass


def find_executable(configured=None, environ=None):
    """The toposimp to run: the configured path if any, else `toposimp` on PATH."""
    environ = os.environ if environ is None else environ
    if configured:
        configured = os.path.expanduser(configured)
        if os.path.isdir(configured):
            configured = os.path.join(configured, "toposimp")
        if os.path.isfile(configured) and os.access(configured, os.X_OK):
            return configured
        raise ExecutableNotFound(
            "the toposimp executable set in the provider settings ({}) does not exist or cannot be run".format(configured))
    found = shutil.which("toposimp", path=environ.get("PATH", os.defpath))
    if not found:
        raise ExecutableNotFound(
            "toposimp was not found on PATH; install it (cmake --install, or the Debian package) "
            "or set its path in Settings > Options > Processing > Providers > toposimp")
    return found


def overall_percent(phase, percent):
    """A phase's percent mapped onto the whole run's."""
    first, last = PHASE_SPANS.get(phase.split(" ", 1)[0], (0, 100))
    return first + (last - first) * max(0, min(100, percent)) / 100.0


def _warn(feedback, text):
    push = getattr(feedback, "pushWarning", None)
    (push or feedback.pushInfo)(text)


def _forward_stderr(stream, feedback, messages, lock):
    """Reads toposimp's stderr line by line: progress to the progress bar, messages to the log."""
    phase = None
    for raw in stream:
        line = raw.rstrip("\n")
        if line.startswith("PROGRESS "):
            parts = line.split(" ", 2)
            if len(parts) == 3 and parts[1].isdigit():
                with lock:
                    if parts[2] != phase:
                        phase = parts[2]
                        feedback.setProgressText(phase)
                    feedback.setProgress(overall_percent(phase, int(parts[1])))
                continue
        if not line:
            continue
        with lock:
            messages.append(line)
            if ": error: " in line:
                pass  # the run fails; run() raises ToolError with these lines as its message
            elif ": warning: " in line:
                _warn(feedback, line.split(": warning: ", 1)[1])
            else:
                feedback.pushInfo(line)


def run(executable, args, feedback, poll_seconds=0.1, stop_seconds=10.0):
    """Runs `executable args...`; returns (exit status 0 or 1, stdout text).

    Raises Cancelled when feedback.isCanceled() turns true (the process gets SIGTERM, on which
    toposimp removes what it was writing, and SIGKILL after `stop_seconds`), ToolError when it
    exits with another status."""
    feedback.pushInfo("toposimp command: " + " ".join(_quote(a) for a in [executable] + list(args)))
    process = subprocess.Popen([executable] + list(args), stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                               stdin=subprocess.DEVNULL, text=True, encoding="utf-8", errors="replace")
    messages = []
    lock = threading.Lock()
    out_chunks = []
    readers = [
        threading.Thread(target=_forward_stderr, args=(process.stderr, feedback, messages, lock), daemon=True),
        threading.Thread(target=lambda: out_chunks.append(process.stdout.read()), daemon=True),
    ]
    for reader in readers:
        reader.start()
    cancelled = False
    while process.poll() is None:
        if feedback.isCanceled():
            cancelled = True
            process.terminate()
            try:
                process.wait(stop_seconds)
            except subprocess.TimeoutExpired:
                process.kill()
                process.wait()
            break
        time.sleep(poll_seconds)
    for reader in readers:
        reader.join()
    process.stdout.close()
    process.stderr.close()
    if cancelled:
        raise Cancelled("toposimp was stopped; nothing was written")
    code = process.returncode
    if code in (0, 1):
        return code, "".join(out_chunks)
    errors = [m.split(": error: ", 1)[1] for m in messages if ": error: " in m]
    if code < 0:
        detail = "toposimp was killed by signal {}".format(-code)
    else:
        detail = "; ".join(errors) or "\n".join(messages[-5:]) or "no message"
    raise ToolError(detail, code)


def parse_summary(stdout):
    """The --json summary toposimp printed (its last line that is a JSON object), or {}."""
    for line in reversed(stdout.splitlines()):
        line = line.strip()
        if line.startswith("{"):
            try:
                return json.loads(line)
            except ValueError:
                return {}
    return {}


_mesh_formats = {}


def mesh_formats(executable, timeout=30):
    """The mesh formats `toposimp formats --json` lists ({name, title, extension, carries,
    text_and_binary} each): the table in toposimp's source (io/mesh/mesh_files.cpp) is their only
    list. Asked once per executable; [] if it cannot say."""
    if executable not in _mesh_formats:
        formats = []
        try:
            done = subprocess.run([executable, "formats", "--json"], capture_output=True, text=True, timeout=timeout,
                                  stdin=subprocess.DEVNULL)
            if done.returncode == 0:
                formats = json.loads(done.stdout).get("mesh_formats", [])
        except (OSError, ValueError, subprocess.SubprocessError):
            formats = []
        _mesh_formats[executable] = formats
    return _mesh_formats[executable]


def mesh_file_filters(formats):
    """QGIS file filters for mesh files in `formats`: (input, output). Outputs list PLY first,
    the default, as it keeps every attribute; with no formats known, any file."""
    if not formats:
        return "All files (*)", "All files (*)"
    patterns = ["*" + f["extension"].lower() for f in formats] + ["*" + f["extension"].upper() for f in formats]
    ordered = sorted(formats, key=lambda f: f["name"] != "ply")
    outputs = ";;".join("{} (*{})".format(f["title"], f["extension"].lower()) for f in ordered)
    return "Meshes ({})".format(" ".join(patterns)), outputs


def _quote(arg):
    if arg and all(c.isalnum() or c in "-_./:=%+," for c in arg):
        return arg
    return "'" + arg.replace("'", "'\\''") + "'"

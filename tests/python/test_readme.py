"""The README's "Use from Python" example runs as it is, from the repository's root."""
import os
import pathlib
import re
import subprocess
import sys

ROOT = pathlib.Path(__file__).resolve().parents[2]


def test_readme_example_runs():
    text = (ROOT / "README.md").read_text()
    section = text[text.index("## Use from Python"):]
    code = re.search(r"```python\n(.*?)```", section, re.S).group(1)
    done = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, env=dict(os.environ))
    assert done.returncode == 0, done.stderr
    vertices, _ = done.stdout.split("\n", 1)
    before, after = re.match(r"(\d+) -> (\d+) vertices", vertices).groups()
    assert int(after) < int(before)
    assert "border_no_longer_shared" in done.stdout

"""The README's example runs as written."""
import os
import subprocess
import sys

from conftest import ROOT


def test_quickstart_runs(tmp_path):
    r = subprocess.run([sys.executable, os.path.join(ROOT, "examples", "quickstart.py"), str(tmp_path)],
                       capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    assert "visible triangles of" in r.stdout
    assert (tmp_path / "ball.glb").stat().st_size > 1000

import os
import shutil
import subprocess
import sys

import pytest

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))


@pytest.fixture(scope="session")
def vdiso_bin():
    """The vdiso command line, built beside the module (ctest passes VDISO_BIN)."""
    path = os.environ.get("VDISO_BIN") or shutil.which("vdiso") or os.path.join(ROOT, "build", "bin", "vdiso")
    if not os.path.exists(path):
        pytest.fail(f"the vdiso command line is not at {path}: build it (scripts/build.sh) or set VDISO_BIN")
    return path


def run(args, **kw):
    return subprocess.run(args, capture_output=True, text=True, **kw)


def python_child(code, *, env_extra=None, **kw):
    """Runs `code` in a fresh interpreter with the same module path."""
    env = dict(os.environ)
    env.update(env_extra or {})
    return subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True, env=env, **kw)

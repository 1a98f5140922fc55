import os
import shutil
import signal
import subprocess
import sys
import time

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


def at_once(work, threads=4):
    """Runs work() on `threads` Python threads at once; returns what each returned and what any
    raised."""
    import threading
    results, errors = [], []

    def one():
        try:
            results.append(work())
        except Exception as e:  # noqa: BLE001 (the caller looks at them)
            errors.append(e)

    started = [threading.Thread(target=one) for _ in range(threads)]
    for t in started:
        t.start()
    for t in started:
        t.join()
    return results, errors


def interrupt(child):
    """Ctrl-C to a child mid-call: it must end by KeyboardInterrupt before printing "done".
    Returns the seconds it took."""
    sent = time.monotonic()
    child.send_signal(signal.SIGINT)
    stdout, stderr = child.communicate(timeout=60)
    waited = time.monotonic() - sent
    assert child.returncode != 0 and "KeyboardInterrupt" in stderr, stderr
    assert "done" not in stdout
    return waited

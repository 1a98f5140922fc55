#!/usr/bin/python3
"""Run Debian's nginx (package nginx-light) on a loopback port for tests.

Serves --root as static files (Range -> 206, ETag, If-Match/If-None-Match)
from a private temporary prefix (config, pid file, logs, temp folders); no
system file is read or written. nginx cannot listen on port 0 and report the
port, so this launcher asks the OS for a free port (bind 127.0.0.1:0, read
it, close), starts nginx on it and checks with GET /__whoami (a random token
in the config) that the nginx answering is ours; if nginx failed to bind
(another process took the port in between) it retries with a new port.

Output: first line "PORT <n>", second line "PREFIX <dir>" (access.log there
records "$request $status $body_bytes_sent $http_range $http_if_match").
It stops nginx and removes the prefix when stdin closes (if stdin is a pipe),
after --lifetime seconds, when --parent-pid is gone, on SIGTERM/SIGINT, or if
nginx dies. nginx itself also gets SIGTERM if this launcher is killed
(PR_SET_PDEATHSIG).

usage: /usr/bin/python3 tests/remote/start_nginx.py --root DIR [--lifetime S]
       [--tls CERT KEY] [--parent-pid PID] [--port-file F] [--tmpdir D]
       [--keep-prefix]
"""

import argparse
import ctypes
import http.client
import os
import secrets
import shutil
import signal
import socket
import ssl
import stat
import subprocess
import sys
import tempfile
import threading
import time

HERE = os.path.dirname(os.path.abspath(__file__))
NGINX = shutil.which("nginx", path="/usr/sbin:/usr/bin:/sbin:/bin") or "/usr/sbin/nginx"


def free_port():
    s = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
    s.bind(("127.0.0.1", 0))
    port = s.getsockname()[1]
    s.close()
    return port


def pdeathsig():
    try:
        libc = ctypes.CDLL("libc.so.6", use_errno=True)
        libc.prctl(1, signal.SIGTERM)  # PR_SET_PDEATHSIG
    except OSError:
        pass
    os.setpgid(0, 0)  # own process group: a Ctrl-C to the test is for us


def whoami(port, tls, timeout=0.5):
    try:
        if tls:
            ctx = ssl.create_default_context()
            ctx.check_hostname = False
            ctx.verify_mode = ssl.CERT_NONE
            c = http.client.HTTPSConnection("127.0.0.1", port, timeout=timeout, context=ctx)
        else:
            c = http.client.HTTPConnection("127.0.0.1", port, timeout=timeout)
        c.request("GET", "/__whoami")
        r = c.getresponse()
        body = r.read().decode(errors="replace").strip()
        c.close()
        return body
    except (OSError, http.client.HTTPException):
        return None


def start(cfg, prefix):
    with open(os.path.join(HERE, "nginx.conf.in")) as f:
        template = f.read()
    for attempt in range(10):
        port = free_port()
        token = secrets.token_hex(8)
        tls_conf = ""
        if cfg.tls:
            tls_conf = ("        ssl_certificate %s;\n        ssl_certificate_key %s;\n"
                        % (os.path.abspath(cfg.tls[0]), os.path.abspath(cfg.tls[1])))
        conf = (template.replace("@PREFIX@", prefix).replace("@PORT@", str(port))
                .replace("@ROOT@", cfg.root).replace("@TOKEN@", token)
                .replace("@TLS@", "ssl" if cfg.tls else "")
                .replace("@TLS_CONF@", tls_conf))
        conf_path = os.path.join(prefix, "nginx.conf")
        with open(conf_path, "w") as f:
            f.write(conf)
        err_path = os.path.join(prefix, "error.log")
        with open(err_path, "w"):
            pass
        proc = subprocess.Popen([NGINX, "-p", prefix + "/", "-c", conf_path, "-e", err_path],
                                stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                                stderr=open(os.path.join(prefix, "stderr.log"), "w"),
                                preexec_fn=pdeathsig)
        deadline = time.time() + 10
        while time.time() < deadline:
            if proc.poll() is not None:
                break
            if whoami(port, cfg.tls) == token:
                return proc, port
            time.sleep(0.05)
        if proc.poll() is None:  # answering, but not our token: someone else's port
            proc.terminate()
            proc.wait()
        with open(err_path) as f:
            log = f.read()
        with open(os.path.join(prefix, "stderr.log")) as f:
            log += f.read()
        if "Address already in use" in log or proc.returncode is None:
            continue
        sys.stderr.write("start_nginx.py: nginx failed (exit %s):\n%s" % (proc.returncode, log))
        return None, 0
    sys.stderr.write("start_nginx.py: no free port after 10 tries\n")
    return None, 0


def main():
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--root", required=True, help="folder to serve")
    ap.add_argument("--lifetime", type=float, default=600)
    ap.add_argument("--tls", nargs=2, metavar=("CERT", "KEY"))
    ap.add_argument("--parent-pid", type=int, default=0)
    ap.add_argument("--port-file")
    ap.add_argument("--tmpdir", help="make the prefix in this folder (default: $TMPDIR or /tmp)")
    ap.add_argument("--keep-prefix", action="store_true", help="do not delete the prefix")
    cfg = ap.parse_args()
    cfg.root = os.path.abspath(cfg.root)
    if not os.path.isdir(cfg.root):
        ap.error("--root %s is not a folder" % cfg.root)
    if not os.path.exists(NGINX):
        sys.stderr.write("start_nginx.py: %s missing: apt-get install -y nginx-light\n" % NGINX)
        return 2

    prefix = tempfile.mkdtemp(prefix="vdiso-nginx-", dir=cfg.tmpdir)
    stop = threading.Event()
    for sig in (signal.SIGTERM, signal.SIGINT, signal.SIGHUP):
        signal.signal(sig, lambda *_: stop.set())
    proc, port = start(cfg, prefix)
    if proc is None:
        if not cfg.keep_prefix:
            shutil.rmtree(prefix, ignore_errors=True)
        return 1
    if cfg.port_file:
        with open(cfg.port_file + ".tmp", "w") as f:
            f.write("%d\n" % port)
        os.replace(cfg.port_file + ".tmp", cfg.port_file)
    sys.stdout.write("PORT %d\nPREFIX %s\n" % (port, prefix))
    sys.stdout.flush()

    try:
        mode = os.fstat(0).st_mode
        if stat.S_ISFIFO(mode) or stat.S_ISSOCK(mode):
            def watch_stdin():
                try:
                    while os.read(0, 4096):
                        pass
                except OSError:
                    pass
                stop.set()
            threading.Thread(target=watch_stdin, daemon=True).start()
    except OSError:
        pass

    end = time.time() + cfg.lifetime
    while not stop.is_set() and time.time() < end and proc.poll() is None:
        if cfg.parent_pid:
            try:
                os.kill(cfg.parent_pid, 0)
            except ProcessLookupError:
                break
            except PermissionError:
                pass
        stop.wait(0.2)
    if proc.poll() is None:
        proc.terminate()
        try:
            proc.wait(5)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()
    if not cfg.keep_prefix:
        shutil.rmtree(prefix, ignore_errors=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())

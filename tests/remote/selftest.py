#!/usr/bin/python3
"""Self-test of the remote-store test servers, with the curl CLI (same
libcurl and SigV4 signer as vdiso). Needs: curl, openssl, python3-botocore,
nginx-light. usage: /usr/bin/python3 tests/remote/selftest.py
Exit 0 when every check passed; the last line is "N passed, N failed"."""

import hashlib
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
PY = "/usr/bin/python3"
SIG = ["--aws-sigv4", "aws:amz:us-east-1:s3"]
UNSIGNED = ["-H", "x-amz-content-sha256: UNSIGNED-PAYLOAD"]
results = {"passed": 0, "failed": 0}


def check(name, ok, detail=""):
    results["passed" if ok else "failed"] += 1
    print("%s %s%s" % ("ok  " if ok else "FAIL", name, "" if ok else "  -- " + str(detail)))
    sys.stdout.flush()


def curl(*args, timeout=20):
    """Return (exit code, http status, body bytes, headers text)."""
    fd, hdr = tempfile.mkstemp()
    os.close(fd)
    try:
        p = subprocess.run(["curl", "-s", "-D", hdr, "-w", "\n%{http_code}"] + list(args),
                           capture_output=True, timeout=timeout)
        out = p.stdout
        body, _, code = out.rpartition(b"\n")
        with open(hdr, "rb") as f:
            headers = f.read().decode(errors="replace")
        return p.returncode, int(code or 0), body, headers
    finally:
        os.unlink(hdr)


def header(headers, name):
    for line in headers.splitlines():
        k, _, v = line.partition(":")
        if k.strip().lower() == name.lower():
            return v.strip()
    return None


def start(cmd):
    p = subprocess.Popen(cmd, stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
    first = p.stdout.readline().split()
    if len(first) != 2 or first[0] != "PORT":
        raise SystemExit("server did not start: %r" % first)
    return p, int(first[1])


def stop(p):
    p.stdin.close()
    p.wait(10)


def main():
    tmp = tempfile.mkdtemp(prefix="vdiso-remote-selftest-")
    try:
        run(tmp)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    print("%d passed, %d failed" % (results["passed"], results["failed"]))
    return 0 if results["failed"] == 0 else 1


def run(tmp):
    root = os.path.join(tmp, "root")
    os.makedirs(os.path.join(root, "bkt", "dir"))
    os.makedirs(os.path.join(root, "pub"))
    data = bytes((i * 7 + 3) % 256 for i in range(100000))
    with open(os.path.join(root, "bkt", "obj.bin"), "wb") as f:
        f.write(data)
    with open(os.path.join(root, "bkt", "a b+c.txt"), "wb") as f:
        f.write(b"plus")
    with open(os.path.join(root, "pub", "hello.txt"), "wb") as f:
        f.write(b"hello\n")
    md5 = '"%s"' % hashlib.md5(data).hexdigest()
    subprocess.run(["sh", os.path.join(HERE, "gen_cert.sh"), os.path.join(tmp, "tls")],
                   check=True, capture_output=True)
    subprocess.run(["sh", os.path.join(HERE, "gen_cert.sh"), os.path.join(tmp, "tls"), "other"],
                   check=True, capture_output=True)
    crt, key = os.path.join(tmp, "tls", "server.crt"), os.path.join(tmp, "tls", "server.key")
    other = os.path.join(tmp, "tls", "other.crt")

    s3 = [PY, os.path.join(HERE, "s3_server.py"), "--root", root, "--cred", "AK:SK",
          "--cred", "TAK:TSK:TOKEN", "--public", "pub", "--lifetime", "300"]
    p, port = start(s3)
    B = "http://127.0.0.1:%d" % port
    obj = B + "/bkt/obj.bin"
    ak = SIG + ["--user", "AK:SK"] + UNSIGNED

    def ctl(*ops):
        rc, code, body, _ = curl("-X", "POST", "--data", json.dumps(list(ops)), B + "/__control")
        assert code == 200, body

    try:
        rc, code, body, h = curl(*ak, obj)
        check("signed GET", code == 200 and body == data and header(h, "ETag") == md5,
              (code, header(h, "ETag")))
        check("Last-Modified, Accept-Ranges", header(h, "Last-Modified") and
              header(h, "Accept-Ranges") == "bytes", h)
        rc, code, body, h = curl(*SIG, "--user", "AK:WRONG", *UNSIGNED, obj)
        check("wrong secret -> 403 SignatureDoesNotMatch",
              code == 403 and b"<Code>SignatureDoesNotMatch</Code>" in body, (code, body[:200]))
        rc, code, body, h = curl(*SIG, "--user", "AK:SK", obj)
        check("no x-amz-content-sha256 -> 400 (as S3)", code == 400, code)
        rc, code, body, h = curl(*SIG, "--user", "AK:SK", "-H", "x-amz-content-sha256: "
                                 + hashlib.sha256(b"").hexdigest(), obj)
        check("empty-body hash accepted", code == 200, code)
        rc, code, body, h = curl(*SIG, "--user", "TAK:TSK", *UNSIGNED,
                                 "-H", "x-amz-security-token: TOKEN", "-r", "0-99", obj)
        check("session token + range 0-99 -> 206", code == 206 and body == data[:100] and
              header(h, "Content-Range") == "bytes 0-99/100000", (code, h))
        rc, code, body, h = curl(*SIG, "--user", "TAK:TSK", *UNSIGNED,
                                 "-H", "x-amz-security-token: BAD", obj)
        check("bad session token rejected", code in (400, 403) and b"InvalidToken" in body, code)
        rc, code, body, h = curl("-I", *ak, obj)
        check("HEAD", code == 200 and header(h, "Content-Length") == "100000", h)
        rc, code, body, h = curl(*ak, "-r", "-10", obj)
        check("suffix range", code == 206 and body == data[-10:], code)
        rc, code, body, h = curl(*ak, "-r", "100000-", obj)
        check("unsatisfiable range -> 416", code == 416 and
              header(h, "Content-Range") == "bytes */100000", (code, h))
        rc, code, body, h = curl(*ak, "-H", "If-Match: " + md5, "-r", "0-9", obj)
        check("If-Match equal -> 206", code == 206, code)
        rc, code, body, h = curl(*ak, "-H", 'If-Match: "0123"', "-r", "0-9", obj)
        check("If-Match differs -> 412", code == 412 and b"PreconditionFailed" in body, code)
        rc, code, body, h = curl(*ak, "-H", "If-None-Match: " + md5, obj)
        check("If-None-Match equal -> 304", code == 304, code)
        rc, code, body, h = curl(*ak, B + "/bkt/missing")
        check("404 NoSuchKey", code == 404 and b"<Code>NoSuchKey</Code>" in body, code)
        rc, code, body, h = curl(*ak, B + "/nobucket/x")
        check("404 NoSuchBucket", code == 404 and b"<Code>NoSuchBucket</Code>" in body, code)
        rc, code, body, h = curl(*ak, B + "/bkt/a%20b%2Bc.txt")
        check("key with space and plus (%20, %2B)", code == 200 and body == b"plus", code)
        rc, code, body, h = curl(*ak, "--resolve", "bkt.s3.localhost:%d:127.0.0.1" % port,
                                 "http://bkt.s3.localhost:%d/obj.bin" % port)
        check("virtual-host style bkt.s3.localhost", code == 200 and body == data, code)
        rc, code, body, h = curl(*ak, B + "/bkt?list-type=2&prefix=a")
        check("ListObjectsV2", code == 200 and b"<Key>a b+c.txt</Key>" in body, code)
        rc, code, body, h = curl(B + "/pub/hello.txt")
        check("anonymous read of public bucket", code == 200 and body == b"hello\n", code)
        rc, code, body, h = curl(obj)
        check("anonymous read of private bucket -> 403 AccessDenied",
              code == 403 and b"AccessDenied" in body, code)

        # faults
        ctl({"op": "reset_stats"}, {"op": "fault", "action": "delay", "ms": 400})
        t = time.time()
        rc, code, body, h = curl(*ak, obj)
        check("delay 400 ms", code == 200 and time.time() - t >= 0.4, time.time() - t)
        ctl({"op": "fault", "action": "status", "status": 503, "count": 2})
        codes = [curl(*ak, obj)[1] for _ in range(3)]
        check("503 x2 then 200", codes == [503, 503, 200], codes)
        for st in (500, 403, 404):
            ctl({"op": "fault", "action": "status", "status": st})
            check("injected %d" % st, curl(*ak, obj)[1] == st)
        ctl({"op": "fault", "action": "truncate", "bytes": 1000})
        rc, code, body, h = curl(*ak, obj)
        check("truncate after 1000 bytes (curl 18)", rc == 18 and len(body) == 1000,
              (rc, len(body)))
        ctl({"op": "fault", "action": "truncate", "bytes": 1000, "rst": True})
        rc, code, body, h = curl(*ak, obj)
        check("reset mid-body (curl 56)", rc == 56, rc)
        ctl({"op": "fault", "action": "drop"})
        rc, code, body, h = curl(*ak, obj)
        check("no response at all (curl 52)", rc == 52, rc)
        ctl({"op": "fault", "action": "bad_content_range"})
        rc, code, body, h = curl(*ak, "-r", "10-19", obj)
        check("wrong Content-Range", code == 206 and
              header(h, "Content-Range") == "bytes 11-20/100000", header(h, "Content-Range"))
        ctl({"op": "fault", "action": "ignore_range"})
        rc, code, body, h = curl(*ak, "-r", "10-19", obj)
        check("Range ignored -> 200 full body", code == 200 and len(body) == 100000, code)
        ctl({"op": "fault", "action": "hang"})
        t = time.time()
        rc, code, body, h = curl(*ak, "-m", "1", obj)
        check("hang until the client gives up (curl 28)", rc == 28 and time.time() - t < 3, rc)
        ctl({"op": "fault", "action": "truncate", "bytes": 500, "hang": True})
        rc, code, body, h = curl(*ak, "-y", "1", "-Y", "100", obj)
        check("stall mid-body, low-speed abort (curl 28)", rc == 28 and len(body) == 500,
              (rc, len(body)))
        ctl({"op": "fault", "action": "redirect", "status": 307, "count": -1})
        rc, code, body, h = curl(*ak, "-L", "--max-redirs", "3", obj)
        check("307 redirect loop (curl 47)", rc == 47, rc)
        ctl({"op": "clear_faults"}, {"op": "fault", "action": "redirect", "status": 301})
        rc, code, body, h = curl(*ak, "-L", obj)
        check("one 301 then served", code == 200 and body == data, code)
        ctl({"op": "fault", "action": "throttle", "bps": 200000})
        t = time.time()
        rc, code, body, h = curl(*ak, obj)
        check("throttle 200 kB/s", code == 200 and time.time() - t >= 0.35, time.time() - t)
        ctl({"op": "fault", "action": "status", "status": 500, "skip": 1, "key": "/pub/*"})
        codes = [curl(B + "/pub/hello.txt")[1] for _ in range(3)]
        check("skip 1 then 500 once, by key glob", codes == [200, 500, 200], codes)
        rc, code, body, h = curl(*ak, "-I", obj)
        old = header(h, "ETag")
        ctl({"op": "put", "bucket": "bkt", "key": "obj.bin", "text": "replaced"})
        rc, code, body, h = curl(*ak, "-H", "If-Match: " + old, obj)
        check("replaced object: old ETag -> 412", code == 412, code)
        rc, code, body, h = curl(*ak, obj)
        check("replaced object: new content", body == b"replaced" and header(h, "ETag") != old)
        rc, code, body, h = curl(B + "/__stats")
        st = json.loads(body)
        po = st["paths"]["/bkt/obj.bin"]
        check("stats count requests and bytes by path",
              po["by_method"]["GET"] >= 14 and st["paths"]["/pub/hello.txt"]["requests"] == 3
              and po["bytes"] > 0, po)
    finally:
        stop(p)
    check("s3_server exits when stdin closes", p.returncode == 0, p.returncode)

    # TLS
    p, port = start(s3 + ["--tls", crt, key])
    try:
        url = "https://127.0.0.1:%d/bkt/obj.bin" % port
        rc, code, body, h = curl("--cacert", crt, *ak, "-r", "0-3", url)
        check("TLS with the right CA", code == 206 and body == b"repl", (rc, code))
        rc, code, body, h = curl("--cacert", other, *ak, url)
        check("TLS with a wrong CA fails (curl 60)", rc == 60, rc)
    finally:
        stop(p)

    # nginx
    p, port = start([PY, os.path.join(HERE, "start_nginx.py"), "--root", root,
                     "--lifetime", "120", "--tmpdir", tmp])
    try:
        url = "http://127.0.0.1:%d/bkt/dir/../a%%20b%%2Bc.txt" % port
        rc, code, body, h = curl("-r", "0-1", url)
        check("nginx range -> 206", code == 206 and body == b"pl", (rc, code))
        etag = header(h, "ETag")
        rc, code, body, h = curl("-H", "If-Match: " + str(etag), "-r", "0-1", url)
        check("nginx If-Match equal -> 206", code == 206, code)
        rc, code, body, h = curl("-H", 'If-Match: "x"', "-r", "0-1", url)
        check("nginx If-Match differs -> 412", code == 412, code)
    finally:
        stop(p)
    p, port = start([PY, os.path.join(HERE, "start_nginx.py"), "--root", root,
                     "--lifetime", "120", "--tmpdir", tmp, "--tls", crt, key])
    try:
        rc, code, body, h = curl("--cacert", crt, "-r", "0-4",
                                 "https://localhost:%d/pub/hello.txt" % port)
        check("nginx TLS range", code == 206 and body == b"hello", (rc, code))
    finally:
        stop(p)


if __name__ == "__main__":
    sys.exit(main())

#!/usr/bin/python3
"""vdiso serve under hostile clients, measured from outside as a user would see it: the server
is its own process (build/bin/vdiso serve), the clients raw WebSocket sockets of this script.

  1. A connection flooding small invalid messages without reading a reply, for SECONDS: the
     server's resident memory before, after and at its peak (VmHWM).
  2. 4 clients that never read, each sending a VIEW every 10 ms at a new isovalue (every frame's
     chunks new): seconds from each one's connection to the server closing it, at the default
     write timeout (30 s; docs/protocol.md).

    bench/serve_hostile.py [SECONDS]          (default 10; makes data/bench/head256.vdiso)
"""
import os
import socket
import struct
import subprocess
import sys
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
VDISO = os.path.join(ROOT, "build", "bin", "vdiso")
STORE = os.path.join(ROOT, "data", "bench", "head256.vdiso")
TOKEN = "0123456789abcdef0123"


def frame(payload):
    """A masked binary WebSocket frame (RFC 6455)."""
    mask = b"\x12\x34\x56\x78"
    n = len(payload)
    head = bytes([0x82]) + (bytes([0x80 | n]) if n < 126 else bytes([0x80 | 126]) + struct.pack(">H", n))
    return head + mask + bytes(b ^ mask[i % 4] for i, b in enumerate(payload))


def view(seq, iso, turn):
    """A VIEW (docs/protocol.md) of the 256^3 head from a side, turned by `turn` radians."""
    import math
    eye = (128 + 600 * math.cos(turn), 128 + 600 * math.sin(turn), 128.0)
    return frame(struct.pack("<BBHIIIII", 1, 1, 0, seq, 0, 1024, 1024, 0) +
                 struct.pack("<3d3d3ddd", *eye, 128.0, 128.0, 128.0, 0.0, 0.0, 1.0, 30.0, iso))


def connect(port, small_buffer=True):
    s = socket.socket()
    if small_buffer:
        s.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4096)
    s.connect(("127.0.0.1", port))
    host = "127.0.0.1:%d" % port
    s.sendall(("GET /ws?token=%s HTTP/1.1\r\nHost: %s\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n"
               "Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\nSec-WebSocket-Version: 13\r\n"
               "Origin: http://%s\r\n\r\n" % (TOKEN, host, host)).encode())
    s.setblocking(False)
    return s


def memory(pid):
    fields = {}
    for line in open("/proc/%d/status" % pid):
        key, _, value = line.partition(":")
        if key in ("VmRSS", "VmHWM"):
            fields[key] = int(value.split()[0]) / 1024.0
    return fields


def closed(s):
    """Whether the server closed the socket (a send fails)."""
    try:
        s.send(frame(b"\x2a\x01\x00\x00\x00\x00\x00\x00"))
        return False
    except BlockingIOError:
        return False
    except OSError:
        return True


def main():
    seconds = float(sys.argv[1]) if len(sys.argv) > 1 else 10.0
    os.makedirs(os.path.dirname(STORE), exist_ok=True)
    if not os.path.exists(STORE):
        subprocess.run([VDISO, "synth", STORE, "--kind", "head", "--size", "256", "--quiet"], check=True)
    server = subprocess.Popen([VDISO, "serve", STORE, "--port", "0", "--token", TOKEN, "--iso", "600.5"],
                              stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
    try:
        line = server.stdout.readline()
        port = int(line.split("127.0.0.1:")[1].split("/")[0])
        time.sleep(0.5)
        before = memory(server.pid)
        flood = connect(port)
        bad = frame(b"\x2a\x01\x00\x00\x00\x00\x00\x00") * 64
        sent, until = 0, time.monotonic() + seconds
        while time.monotonic() < until:
            try:
                sent += flood.send(bad)
            except BlockingIOError:
                time.sleep(0.001)
        after = memory(server.pid)
        print("flood of bad messages, %.0f s, never read: %.1f MB sent; server RSS %.1f -> %.1f MB "
              "(peak %.1f MB): +%.1f MB" % (seconds, sent / 2 ** 20, before["VmRSS"], after["VmRSS"],
                                           after["VmHWM"], after["VmRSS"] - before["VmRSS"]))
        flood.close()

        clients = [connect(port) for _ in range(4)]
        start = time.monotonic()
        dropped = [None] * len(clients)
        seq = 0
        while None in dropped and time.monotonic() - start < 120:
            seq += 1
            for k, c in enumerate(clients):
                if dropped[k] is not None:
                    continue
                try:
                    c.send(view(seq, 400.5 + (seq % 64) * 5, 0.3 * seq + k))
                except BlockingIOError:
                    pass
                except OSError:
                    dropped[k] = time.monotonic() - start
            time.sleep(0.01)
        print("4 clients that never read, a VIEW every 10 ms each: dropped after %s s "
              "(write timeout 30 s)" % ", ".join("%.1f" % d if d is not None else "never" for d in dropped))
    finally:
        server.terminate()
        server.wait()


if __name__ == "__main__":
    main()

#!/usr/bin/python3
"""Small S3-style test server for vdiso's remote-store tests.

Independent of vdiso: it verifies AWS SigV4 header signatures with botocore's
signer (Debian package python3-botocore), serves objects from a folder
(bucket = first-level subfolder, key = the rest of the path) and can inject
faults. Loopback only, port chosen by the OS, bounded lifetime.

Run with Debian's interpreter: /usr/bin/python3 tests/remote/s3_server.py -h
The first line on stdout is "PORT <n>". See tests/remote/README.md.
"""

import argparse
import base64
import calendar
import datetime
import email.utils
import fnmatch
import hashlib
import hmac
import html
import json
import os
import re
import select
import signal
import socket
import ssl
import stat
import struct
import sys
import tempfile
import threading
import time
import urllib.parse
import uuid
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer

try:
    from botocore.auth import S3SigV4Auth
    from botocore.awsrequest import AWSRequest
    from botocore.credentials import Credentials
except ImportError:  # pragma: no cover
    sys.stderr.write("s3_server.py: botocore missing; run it with /usr/bin/python3 "
                     "and `apt-get install -y python3-botocore`\n")
    sys.exit(2)

if not os.path.realpath(sys.modules["botocore.auth"].__file__).startswith("/usr/lib/python3/"):
    sys.stderr.write("s3_server.py: warning: botocore from %s, not Debian's python3-botocore; "
                     "run with /usr/bin/python3\n" % sys.modules["botocore.auth"].__file__)

EMPTY_SHA256 = hashlib.sha256(b"").hexdigest()
UNSIGNED_PAYLOAD = "UNSIGNED-PAYLOAD"
CHUNK = 64 * 1024

ERROR_MESSAGES = {
    "AccessDenied": "Access Denied",
    "AuthorizationHeaderMalformed": "The authorization header is malformed",
    "BadRequest": "Bad Request",
    "InternalError": "We encountered an internal error. Please try again.",
    "InvalidAccessKeyId": "The AWS Access Key Id you provided does not exist in our records.",
    "InvalidArgument": "Invalid Argument",
    "InvalidRange": "The requested range is not satisfiable",
    "InvalidRequest": "Invalid Request",
    "InvalidToken": "The provided token is malformed or otherwise invalid.",
    "MethodNotAllowed": "The specified method is not allowed against this resource.",
    "NoSuchBucket": "The specified bucket does not exist",
    "NoSuchKey": "The specified key does not exist.",
    "NotImplemented": "A header you provided implies functionality that is not implemented",
    "PreconditionFailed": "At least one of the pre-conditions you specified did not hold",
    "RequestTimeTooSkewed": "The difference between the request time and the current time is too large.",
    "ServiceUnavailable": "Reduce your request rate.",
    "SignatureDoesNotMatch": "The request signature we calculated does not match the signature "
                             "you provided. Check your key and signing method.",
    "SlowDown": "Please reduce your request rate.",
    "TemporaryRedirect": "Please re-send this request to the specified temporary endpoint.",
    "PermanentRedirect": "The bucket you are attempting to access must be addressed using "
                         "the specified endpoint.",
    "XAmzContentSHA256Mismatch": "The provided 'x-amz-content-sha256' header does not match "
                                 "what was computed.",
}
DEFAULT_CODE_FOR_STATUS = {
    400: "BadRequest", 403: "AccessDenied", 404: "NoSuchKey", 405: "MethodNotAllowed",
    409: "OperationAborted", 412: "PreconditionFailed", 416: "InvalidRange",
    500: "InternalError", 501: "NotImplemented", 503: "SlowDown",
}


class S3Error(Exception):
    def __init__(self, status, code, message=None, extra=None, headers=None):
        super().__init__(code)
        self.status = status
        self.code = code
        self.message = message or ERROR_MESSAGES.get(code, code)
        self.extra = extra or {}
        self.headers = headers or {}


def http_date(ts):
    return email.utils.formatdate(ts, usegmt=True)


def iso8601(ts):
    return datetime.datetime.fromtimestamp(ts, datetime.timezone.utc).strftime(
        "%Y-%m-%dT%H:%M:%S.000Z")


def aws_uri_encode_path(path):
    """S3 canonical URI: decode what arrived, then encode every byte except
    unreserved characters (A-Za-z0-9-_.~) and '/'. S3 does not normalize
    '.'/'..' segments or double slashes. Like S3, a raw '+' in the path is
    decoded as a space (S3 answers with "/a%20b" in <CanonicalRequest> for a
    request to "/a+b"), so a key with '+' must be sent as %2B."""
    return urllib.parse.quote(urllib.parse.unquote_plus(path), safe="/")


def query_pairs(raw_query):
    pairs = []
    for item in raw_query.split("&"):
        if not item:
            continue
        k, _, v = item.partition("=")
        pairs.append((urllib.parse.unquote_plus(k), urllib.parse.unquote_plus(v)))
    return pairs


class ExactHeadersSigner(S3SigV4Auth):
    """botocore's S3 SigV4 signer, signing exactly the headers the client
    listed in SignedHeaders (botocore would otherwise drop user-agent/expect
    and add host on its own)."""

    def __init__(self, credentials, service, region, signed_names):
        super().__init__(credentials, service, region)
        self._signed_names = signed_names

    def headers_to_sign(self, request):
        from botocore.awsrequest import HTTPHeaders
        hm = HTTPHeaders()
        for name in self._signed_names:
            for value in request.headers.get_all(name) or []:
                hm[name] = value
        return hm


class Faults:
    """Fault rules. A rule matches a request (method, "/bucket/key"),
    skips its first `skip` matches, then applies to `count` requests
    (-1 = forever). The first live matching rule wins."""

    ACTIONS = {"none", "delay", "status", "truncate", "drop", "hang",
               "redirect", "bad_content_range", "ignore_range", "throttle", "corrupt", "replaced"}

    def __init__(self):
        self.lock = threading.Lock()
        self.rules = []
        self.next_id = 1

    def add(self, rule):
        rule = dict(rule)
        action = rule.setdefault("action", "none")
        if action not in self.ACTIONS:
            raise ValueError("unknown fault action %r (one of %s)" %
                             (action, ", ".join(sorted(self.ACTIONS))))
        if action == "status" and "status" not in rule:
            raise ValueError("fault action 'status' needs a 'status' field")
        rule.setdefault("key", "*")
        rule.setdefault("methods", ["GET", "HEAD"])
        rule["methods"] = [m.upper() for m in rule["methods"]]
        rule.setdefault("count", 1)
        rule.setdefault("skip", 0)
        rule["hits"] = 0
        with self.lock:
            rule["id"] = self.next_id
            self.next_id += 1
            self.rules.append(rule)
        return rule["id"]

    def clear(self):
        with self.lock:
            self.rules = []

    def take(self, method, path):
        with self.lock:
            for rule in self.rules:
                if method not in rule["methods"]:
                    continue
                if not fnmatch.fnmatchcase(path, rule["key"]):
                    continue
                if rule["skip"] > 0:
                    rule["skip"] -= 1
                    continue
                if rule["count"] == 0:
                    continue
                if rule["count"] > 0:
                    rule["count"] -= 1
                rule["hits"] += 1
                out = dict(rule)
                self.rules = [r for r in self.rules if r["count"] != 0]
                return out
        return None

    def snapshot(self):
        with self.lock:
            return [dict(r) for r in self.rules]


class Stats:
    def __init__(self, keep_log=10000):
        self.lock = threading.Lock()
        self.keep_log = keep_log
        self.reset()

    def reset(self):
        with getattr(self, "lock", threading.Lock()):
            self.total = {"requests": 0, "bytes": 0, "other_bytes": 0, "connections": 0,
                          "by_method": {}, "by_status": {}}
            self.paths = {}
            self.log = []

    def record(self, entry):
        with self.lock:
            method, status, nbytes = entry["method"], str(entry["status"]), entry["bytes"]
            t = self.total
            t["requests"] += 1
            t["bytes"] += nbytes
            t["other_bytes"] += entry["other_bytes"]
            t["by_method"][method] = t["by_method"].get(method, 0) + 1
            t["by_status"][status] = t["by_status"].get(status, 0) + 1
            p = self.paths.setdefault(entry["path"], {"requests": 0, "bytes": 0,
                                                      "other_bytes": 0,
                                                      "by_method": {}, "by_status": {}})
            p["requests"] += 1
            p["bytes"] += nbytes
            p["other_bytes"] += entry["other_bytes"]
            p["by_method"][method] = p["by_method"].get(method, 0) + 1
            p["by_status"][status] = p["by_status"].get(status, 0) + 1
            if len(self.log) < self.keep_log:
                self.log.append(entry)

    def connected(self):
        with self.lock:
            self.total["connections"] += 1

    def snapshot(self):
        with self.lock:
            return json.loads(json.dumps({"total": self.total, "paths": self.paths,
                                          "log": self.log}))


class ETagCache:
    def __init__(self):
        self.lock = threading.Lock()
        self.cache = {}

    def etag(self, path, st):
        ident = (path, st.st_ino, st.st_mtime_ns, st.st_size)
        with self.lock:
            if ident in self.cache:
                return self.cache[ident]
        h = hashlib.md5()
        with open(path, "rb") as f:
            for block in iter(lambda: f.read(1 << 20), b""):
                h.update(block)
        tag = '"%s"' % h.hexdigest()
        with self.lock:
            self.cache[ident] = tag
        return tag


class LinkLimit:
    """One link's bandwidth shared by every connection: a body's bytes leave no faster than
    `mbit` megabits a second in all (bench: a 1 Gbit/s link without tc)."""

    def __init__(self, mbit):
        self.bytes_per_s = mbit * 1e6 / 8
        self.lock = threading.Lock()
        self.free_at = 0.0

    def take(self, n):
        with self.lock:
            start = max(time.monotonic(), self.free_at)
            self.free_at = start + n / self.bytes_per_s
            until = self.free_at
        wait = until - time.monotonic()
        if wait > 0:
            time.sleep(wait)


class S3Server(ThreadingHTTPServer):
    daemon_threads = True
    allow_reuse_address = True
    request_queue_size = 64

    def __init__(self, addr, handler, cfg):
        super().__init__(addr, handler)
        self.cfg = cfg
        self.faults = Faults()
        self.stats = Stats()
        self.etags = ETagCache()
        self.stopping = threading.Event()
        self.link = None  # a LinkLimit with --rate-mbit
        self.ssl_ctx = None
        self.creds = {}
        for c in cfg.cred:
            parts = c.split(":", 2)
            if len(parts) < 2:
                raise SystemExit("--cred wants KEY:SECRET[:TOKEN], got %r" % c)
            self.creds[parts[0]] = (parts[1], parts[2] if len(parts) == 3 else None)
        self.public = set(cfg.public)
        if cfg.tls:
            ctx = ssl.SSLContext(ssl.PROTOCOL_TLS_SERVER)
            ctx.load_cert_chain(cfg.tls[0], cfg.tls[1])
            self.ssl_ctx = ctx

    def finish_request(self, request, client_address):
        if self.ssl_ctx is not None:
            try:
                request.settimeout(10)
                request = self.ssl_ctx.wrap_socket(request, server_side=True)
                request.settimeout(None)
            except (ssl.SSLError, OSError) as e:
                if self.cfg.verbose:
                    sys.stderr.write("s3_server: TLS handshake failed: %s\n" % e)
                return
            try:
                self.RequestHandlerClass(request, client_address, self)
            finally:
                try:
                    request.close()
                except OSError:
                    pass
        else:
            self.RequestHandlerClass(request, client_address, self)

    def handle_error(self, request, client_address):
        if self.cfg.verbose:
            super().handle_error(request, client_address)


class Handler(BaseHTTPRequestHandler):
    protocol_version = "HTTP/1.1"
    # As S3 and nginx do: without it a body written after its headers waits for their ACK,
    # which the client delays by 40 ms on every request of a kept-alive connection but the first.
    disable_nagle_algorithm = True
    timeout = 120  # an idle keep-alive connection is closed after this

    def version_string(self):
        return "AmazonS3"

    def setup(self):  # once a connection, before its first request
        super().setup()
        self.server.stats.connected()

    # ---------------------------------------------------------------- plumbing
    def log_message(self, fmt, *args):
        if self.server.cfg.verbose:
            sys.stderr.write("s3_server: %s - %s\n" % (self.address_string(), fmt % args))

    def do_GET(self):
        self.dispatch("GET")

    def do_HEAD(self):
        self.dispatch("HEAD")

    def do_POST(self):
        self.dispatch("POST")

    def do_PUT(self):
        self.dispatch("PUT")

    def do_DELETE(self):
        self.dispatch("DELETE")

    def read_body(self):
        n = int(self.headers.get("Content-Length") or 0)
        return self.rfile.read(n) if n > 0 else b""

    def dispatch(self, method):
        self.req_id = uuid.uuid4().hex[:16].upper()
        self.sent_bytes = 0  # object data bytes
        self.other_bytes = 0  # XML bodies: errors and listings
        self.status_sent = 0
        raw_path, _, raw_query = self.path.partition("?")
        if raw_path.startswith("/__"):
            return self.control(method, raw_path, raw_query)
        self.stat_path = raw_path
        self.fault = None
        auth_kind = "anon"
        try:
            body = self.read_body()
            host = (self.headers.get("Host") or "").strip()
            bucket, key = self.address(host, raw_path)
            self.stat_path = "/" + bucket + ("/" + key if key else "") if bucket else "/"
            if self.headers.get("Authorization"):
                auth_kind = "sigv4"
                self.verify_sigv4(method, raw_path, raw_query, body)
            elif not (bucket and bucket in self.server.public and method in ("GET", "HEAD")):
                raise S3Error(403, "AccessDenied")
            self.fault = self.server.faults.take(method, self.stat_path)
            if self.fault and self.pre_fault(method):
                return
            if method not in ("GET", "HEAD"):
                raise S3Error(405, "MethodNotAllowed", extra={"Method": method})
            if not bucket:
                return self.list_buckets(method)
            bdir = os.path.join(self.server.cfg.root, bucket)
            if not os.path.isdir(bdir) or bucket.startswith("."):
                raise S3Error(404, "NoSuchBucket", extra={"BucketName": bucket})
            if not key:
                return self.bucket_request(method, bucket, bdir, raw_query)
            self.get_object(method, bucket, key, bdir)
        except S3Error as e:
            self.send_error_xml(method, e)
        except (BrokenPipeError, ConnectionResetError, ssl.SSLError):
            self.close_connection = True
        finally:
            self.server.stats.record({
                "method": method, "path": self.stat_path, "range": self.headers.get("Range"),
                "status": self.status_sent, "bytes": self.sent_bytes,
                "other_bytes": self.other_bytes, "auth": auth_kind,
                "fault": self.fault["action"] if self.fault else None,
                "time": round(time.time(), 3)})

    def address(self, host, raw_path):
        """Return (bucket, key). Virtual-host style when Host is
        <bucket>.<suffix>[:port] for one of --vhost-suffix, else path style."""
        hostname = host.rsplit(":", 1)[0] if not host.endswith("]") else host
        hostname = hostname.lower()
        path = urllib.parse.unquote_plus(raw_path)
        suffixes = self.server.cfg.vhost_suffix
        for suffix in sorted(suffixes, key=len, reverse=True):
            if hostname in suffixes:
                break  # the endpoint itself (e.g. s3.localhost): path style
            if hostname.endswith("." + suffix):
                bucket = hostname[: -len(suffix) - 1]
                return bucket, path[1:] if path.startswith("/") else path
        p = path[1:] if path.startswith("/") else path
        bucket, _, key = p.partition("/")
        return bucket, key

    # ---------------------------------------------------------------- SigV4
    def verify_sigv4(self, method, raw_path, raw_query, body):
        srv = self.server
        auth = self.headers.get("Authorization").strip()
        if not auth.startswith("AWS4-HMAC-SHA256 "):
            raise S3Error(400, "InvalidArgument", "Unsupported Authorization Type",
                          extra={"ArgumentName": "Authorization", "ArgumentValue": auth[:40]})
        fields = {}
        for part in auth[len("AWS4-HMAC-SHA256 "):].split(","):
            k, _, v = part.strip().partition("=")
            fields[k.strip()] = v.strip()
        try:
            cred = fields["Credential"]
            signed = fields["SignedHeaders"].split(";")
            signature = fields["Signature"]
            akid, sdate, region, service, term = cred.split("/")
        except (KeyError, ValueError):
            raise S3Error(400, "AuthorizationHeaderMalformed",
                          "The authorization header is malformed; %s" % auth)
        if akid not in srv.creds:
            raise S3Error(403, "InvalidAccessKeyId", extra={"AWSAccessKeyId": akid})
        secret, token = srv.creds[akid]
        if service != "s3" or term != "aws4_request":
            raise S3Error(400, "AuthorizationHeaderMalformed",
                          "The authorization header is malformed; incorrect service \"%s\". "
                          "This endpoint belongs to \"s3\"." % service)
        if srv.cfg.region != "*" and region != srv.cfg.region:
            raise S3Error(400, "AuthorizationHeaderMalformed",
                          "The authorization header is malformed; the region '%s' is wrong; "
                          "expecting '%s'" % (region, srv.cfg.region),
                          extra={"Region": srv.cfg.region})
        amz_date = self.headers.get("x-amz-date")
        if not amz_date or not re.fullmatch(r"\d{8}T\d{6}Z", amz_date):
            raise S3Error(403, "AccessDenied",
                          "AWS authentication requires a valid Date or x-amz-date header")
        if sdate != amz_date[:8]:
            raise S3Error(400, "AuthorizationHeaderMalformed",
                          "The authorization header is malformed; Invalid credential date. "
                          "Date is not the same as X-Amz-Date.")
        if srv.cfg.max_skew > 0:
            t = calendar.timegm(time.strptime(amz_date, "%Y%m%dT%H%M%SZ"))
            if abs(time.time() - t) > srv.cfg.max_skew:
                raise S3Error(403, "RequestTimeTooSkewed",
                              extra={"RequestTime": amz_date,
                                     "ServerTime": iso8601(time.time())})
        signed_l = [s.lower() for s in signed]
        if "host" not in signed_l:
            raise S3Error(403, "AccessDenied", "host must be a signed header")
        present = {k.lower() for k in self.headers.keys()}
        missing = [s for s in signed_l if s not in present]
        if missing:
            raise S3Error(403, "AccessDenied",
                          "Signed header(s) not present in the request: " + ",".join(missing))
        unsigned = sorted(h for h in present if h.startswith("x-amz-") and h not in signed_l)
        if unsigned:
            raise S3Error(403, "AccessDenied",
                          "There were headers present in the request which were not signed",
                          extra={"HeadersNotSigned": ", ".join(unsigned)})
        got_token = self.headers.get("x-amz-security-token")
        if token is not None and got_token is None:
            raise S3Error(403, "InvalidAccessKeyId",
                          "The AWS Access Key Id needs a security token (x-amz-security-token)",
                          extra={"AWSAccessKeyId": akid})
        if got_token is not None and got_token != token:
            raise S3Error(400, "InvalidToken", extra={"Token-0": got_token})
        content_sha = self.headers.get("x-amz-content-sha256")
        if content_sha is None:
            if srv.cfg.require_content_sha256:
                raise S3Error(400, "InvalidRequest",
                              "Missing required header for this request: x-amz-content-sha256")
        elif content_sha != UNSIGNED_PAYLOAD:
            if not re.fullmatch(r"[0-9a-f]{64}", content_sha):
                raise S3Error(400, "InvalidArgument",
                              "x-amz-content-sha256 must be UNSIGNED-PAYLOAD, or a valid "
                              "sha256 value.",
                              extra={"ArgumentName": "x-amz-content-sha256",
                                     "ArgumentValue": content_sha})
            if content_sha != hashlib.sha256(body).hexdigest():
                raise S3Error(400, "XAmzContentSHA256Mismatch",
                              extra={"ClientComputedContentSHA256": content_sha,
                                     "S3ComputedContentSHA256": hashlib.sha256(body).hexdigest()})

        # Rebuild the request as it arrived and sign it with botocore.
        scheme = "https" if srv.ssl_ctx else "http"
        path = raw_path if srv.cfg.raw_canonical_uri else aws_uri_encode_path(raw_path)
        url = "%s://%s%s" % (scheme, self.headers.get("Host"), path)
        if srv.cfg.raw_canonical_uri and raw_query:
            url += "?" + raw_query
        req = AWSRequest(method=method, url=url, data=body)
        if not srv.cfg.raw_canonical_uri:
            req.params = query_pairs(raw_query)
        for name in self.headers.keys():
            if name.lower() in signed_l and name.lower() not in req.headers:
                for value in self.headers.get_all(name):
                    req.headers[name.lower()] = value
        req.context["timestamp"] = amz_date
        signer = ExactHeadersSigner(Credentials(akid, secret, token), "s3", region, signed_l)
        canonical = signer.canonical_request(req)
        sts = signer.string_to_sign(req, canonical)
        expected = signer.signature(sts, req)
        if not hmac.compare_digest(expected, signature):
            raise S3Error(403, "SignatureDoesNotMatch", extra={
                "AWSAccessKeyId": akid, "StringToSign": sts,
                "SignatureProvided": signature, "CanonicalRequest": canonical})

    # ---------------------------------------------------------------- faults
    def pre_fault(self, method):
        """Faults that act before the object is looked at. True = handled."""
        f = self.fault
        delay = f.get("delay_ms", f.get("ms", 0) if f["action"] == "delay" else 0)
        if delay:
            time.sleep(delay / 1000.0)
        action = f["action"]
        if action == "status":
            status = int(f["status"])
            code = f.get("code") or DEFAULT_CODE_FOR_STATUS.get(status, "InternalError")
            raise S3Error(status, code, f.get("message"), headers=f.get("headers"))
        if action == "drop":
            self.abort_connection(f.get("rst", False))
            return True
        if action == "hang":
            self.hang(f.get("ms"))
            self.close_connection = True
            return True
        if action == "redirect":
            status = int(f.get("status", 307))
            host = self.headers.get("Host") or "127.0.0.1"
            scheme = "https" if self.server.ssl_ctx else "http"
            location = f.get("location") or "%s://%s%s" % (scheme, host, self.path)
            code = "PermanentRedirect" if status == 301 else "TemporaryRedirect"
            raise S3Error(status, code, extra={"Endpoint": host},
                          headers={"Location": location})
        return False

    def abort_connection(self, rst):
        self.close_connection = True
        try:
            self.wfile.flush()
        except OSError:
            pass
        sock = self.connection
        try:
            if rst:
                sock.setsockopt(socket.SOL_SOCKET, socket.SO_LINGER, struct.pack("ii", 1, 0))
            else:
                sock.shutdown(socket.SHUT_RDWR)
        except OSError:
            pass
        try:
            sock.close()
        except OSError:
            pass

    def hang(self, ms=None):
        """Answer nothing until the client closes, the server stops or ms passes."""
        deadline = time.time() + ms / 1000.0 if ms else None
        sock = self.connection
        while not self.server.stopping.is_set():
            if deadline and time.time() >= deadline:
                return
            try:
                r, _, _ = select.select([sock], [], [], 0.2)
                if r:
                    data = sock.recv(4096, socket.MSG_PEEK) if not isinstance(
                        sock, ssl.SSLSocket) else sock.recv(4096)
                    if not data:
                        return
                    if not isinstance(sock, ssl.SSLSocket):
                        sock.recv(len(data))
            except (OSError, ValueError):
                return

    # ---------------------------------------------------------------- responses
    def start_response(self, status, headers):
        self.send_response(status)
        self.status_sent = status
        self.send_header("x-amz-request-id", self.req_id)
        self.send_header("x-amz-id-2", base64.b64encode(self.req_id.encode()).decode())
        for k, v in headers:
            self.send_header(k, v)
        self.end_headers()

    def send_error_xml(self, method, e):
        parts = ["<Code>%s</Code>" % e.code, "<Message>%s</Message>" % html.escape(e.message)]
        for k, v in e.extra.items():
            parts.append("<%s>%s</%s>" % (k, html.escape(str(v)), k))
        parts.append("<RequestId>%s</RequestId>" % self.req_id)
        body = ('<?xml version="1.0" encoding="UTF-8"?>\n<Error>%s</Error>\n'
                % "".join(parts)).encode()
        if e.status == 304:  # no body, no Content-Length
            self.start_response(304, list(e.headers.items()))
            return
        headers = [("Content-Type", "application/xml")]
        headers += list((e.headers or {}).items())
        if method == "HEAD":  # S3 answers HEAD errors without a body
            headers.append(("Content-Length", "0"))
            self.start_response(e.status, headers)
        else:
            headers.append(("Content-Length", str(len(body))))
            self.start_response(e.status, headers)
            self.wfile.write(body)
            self.other_bytes += len(body)

    def send_xml(self, method, xml):
        body = ('<?xml version="1.0" encoding="UTF-8"?>\n' + xml).encode()
        self.start_response(200, [("Content-Type", "application/xml"),
                                  ("Content-Length", str(len(body)))])
        if method != "HEAD":
            self.wfile.write(body)
            self.other_bytes += len(body)

    def list_buckets(self, method):
        root = self.server.cfg.root
        items = []
        for name in sorted(os.listdir(root)):
            p = os.path.join(root, name)
            if os.path.isdir(p) and not name.startswith("."):
                items.append("<Bucket><Name>%s</Name><CreationDate>%s</CreationDate></Bucket>"
                             % (html.escape(name), iso8601(os.stat(p).st_mtime)))
        self.send_xml(method, '<ListAllMyBucketsResult xmlns="http://s3.amazonaws.com/doc/'
                      '2006-03-01/"><Owner><ID>test</ID></Owner><Buckets>%s</Buckets>'
                      '</ListAllMyBucketsResult>\n' % "".join(items))

    def bucket_request(self, method, bucket, bdir, raw_query):
        q = dict(query_pairs(raw_query))
        if method == "HEAD":
            self.start_response(200, [("Content-Length", "0"),
                                      ("x-amz-bucket-region", self.server.cfg.region
                                       if self.server.cfg.region != "*" else "us-east-1")])
            return
        # ListObjectsV2 (list-type=2) and a plain V1 listing without markers.
        prefix = q.get("prefix", "")
        delim = q.get("delimiter", "")
        max_keys = int(q.get("max-keys", "1000"))
        start = q.get("continuation-token") or q.get("start-after") or q.get("marker") or ""
        keys = []
        for dirpath, dirnames, filenames in os.walk(bdir):
            dirnames[:] = [d for d in dirnames if not d.startswith(".")]
            for fn in filenames:
                if fn.startswith(".s3tmp"):
                    continue
                full = os.path.join(dirpath, fn)
                keys.append(os.path.relpath(full, bdir).replace(os.sep, "/"))
        keys.sort()
        contents, prefixes, truncated, last = [], [], False, None
        count = 0
        for k in keys:
            if not k.startswith(prefix) or k <= start:
                continue
            if delim:
                rest = k[len(prefix):]
                if delim in rest:
                    cp = prefix + rest.split(delim, 1)[0] + delim
                    if cp in prefixes or cp <= start:
                        continue
                    if count >= max_keys:
                        truncated = True
                        break
                    prefixes.append(cp)
                    last = cp + "\uffff"
                    count += 1
                    continue
            if count >= max_keys:
                truncated = True
                break
            full = os.path.join(bdir, k)
            st = os.stat(full)
            contents.append(
                "<Contents><Key>%s</Key><LastModified>%s</LastModified><ETag>%s</ETag>"
                "<Size>%d</Size><StorageClass>STANDARD</StorageClass></Contents>"
                % (html.escape(k), iso8601(st.st_mtime),
                   html.escape(self.server.etags.etag(full, st)), st.st_size))
            last = k
            count += 1
        extra = ""
        if truncated and last is not None:
            extra = "<NextContinuationToken>%s</NextContinuationToken>" % html.escape(last)
        self.send_xml(method, '<ListBucketResult xmlns="http://s3.amazonaws.com/doc/2006-03-01/">'
                      "<Name>%s</Name><Prefix>%s</Prefix><KeyCount>%d</KeyCount>"
                      "<MaxKeys>%d</MaxKeys><Delimiter>%s</Delimiter>"
                      "<IsTruncated>%s</IsTruncated>%s%s%s</ListBucketResult>\n"
                      % (html.escape(bucket), html.escape(prefix), count, max_keys,
                         html.escape(delim), "true" if truncated else "false", extra,
                         "".join(contents),
                         "".join("<CommonPrefixes><Prefix>%s</Prefix></CommonPrefixes>"
                                 % html.escape(p) for p in prefixes)))

    def resolve_key(self, bdir, key):
        full = os.path.realpath(os.path.join(bdir, key))
        base = os.path.realpath(bdir)
        if not full.startswith(base + os.sep):
            return None
        return full

    def get_object(self, method, bucket, key, bdir):
        full = self.resolve_key(bdir, key)
        nsk = S3Error(404, "NoSuchKey", extra={"Key": key, "BucketName": bucket})
        if full is None:
            raise nsk
        try:
            f = open(full, "rb")
        except (FileNotFoundError, IsADirectoryError, NotADirectoryError):
            raise nsk
        with f:
            st = os.fstat(f.fileno())
            if not stat.S_ISREG(st.st_mode):
                raise nsk
            size = st.st_size
            etag = self.server.etags.etag(full, st)
            mtime = int(st.st_mtime)
            fault = self.fault or {}
            action = fault.get("action")
            if action == "replaced":  # another version, and If-Match ignored (a broken server)
                etag = fault.get("etag", '"replaced-version"')
            base_headers = [("ETag", etag), ("Last-Modified", http_date(mtime)),
                            ("Accept-Ranges", "bytes"),
                            ("Content-Type", "binary/octet-stream")]
            base_headers += list((fault.get("headers") or {}).items())
            if fault.get("header_bytes"):
                base_headers.append(("X-Padding", "x" * int(fault["header_bytes"])))
            if action != "replaced":
                self.check_conditions(etag, mtime, base_headers)
            start, end, status = 0, size - 1, 200
            rng = self.headers.get("Range")
            if rng is not None and action != "ignore_range":
                parsed = self.parse_range(rng, size)
                if parsed == "unsatisfiable":
                    raise S3Error(416, "InvalidRange",
                                  extra={"RangeRequested": rng, "ActualObjectSize": size},
                                  headers={"Content-Range": "bytes */%d" % size})
                if parsed is not None:
                    start, end = parsed
                    status = 206
            length = end - start + 1 if size else 0
            headers = list(base_headers)
            if status == 206 or action == "bad_content_range":
                status = 206
                if action == "bad_content_range":
                    if "content_range" in fault:
                        cr = fault["content_range"]
                    else:
                        shift = int(fault.get("shift", 1))
                        cr = "bytes %d-%d/%d" % (start + shift, end + shift, size)
                else:
                    cr = "bytes %d-%d/%d" % (start, end, size)
                headers.append(("Content-Range", cr))
            headers.append(("Content-Length", str(length)))
            self.start_response(status, headers)
            if method == "HEAD":
                return
            limit = length
            if action == "truncate":
                limit = min(length, int(fault.get("bytes", length // 2)))
            rate = float(fault.get("bps", 0)) if action == "throttle" else 0.0
            f.seek(start)
            remaining = limit
            t0 = time.time()
            while remaining > 0:
                chunk = f.read(min(CHUNK if not rate else max(1, int(rate / 10)), remaining))
                if not chunk:
                    break
                if action == "corrupt" and remaining == limit:  # the answer's first byte flipped
                    chunk = bytes([chunk[0] ^ 0xFF]) + chunk[1:]
                if self.server.link:
                    self.server.link.take(len(chunk))
                self.wfile.write(chunk)
                self.sent_bytes += len(chunk)
                remaining -= len(chunk)
                if rate:
                    self.wfile.flush()
                    ahead = self.sent_bytes / rate - (time.time() - t0)
                    if ahead > 0:
                        time.sleep(ahead)
            if action == "truncate" and limit < length:
                self.wfile.flush()
                if fault.get("hang"):
                    self.hang(fault.get("ms"))
                self.abort_connection(fault.get("rst", False))

    def check_conditions(self, etag, mtime, headers):
        def etag_in(hdr):
            tags = [t.strip() for t in hdr.split(",")]
            return "*" in tags or etag in tags or etag.strip('"') in tags or \
                ("W/" + etag) in tags

        def parse_date(v):
            try:
                return email.utils.parsedate_to_datetime(v).timestamp()
            except (TypeError, ValueError, IndexError):
                return None

        im = self.headers.get("If-Match")
        ius = self.headers.get("If-Unmodified-Since")
        inm = self.headers.get("If-None-Match")
        ims = self.headers.get("If-Modified-Since")
        if im is not None:
            if not etag_in(im):
                raise S3Error(412, "PreconditionFailed", extra={"Condition": "If-Match"})
        elif ius is not None:
            t = parse_date(ius)
            if t is not None and mtime > t:
                raise S3Error(412, "PreconditionFailed",
                              extra={"Condition": "If-Unmodified-Since"})
        not_modified = S3Error(304, "NotModified", headers=dict(headers[:2]))
        if inm is not None:
            if etag_in(inm):
                raise not_modified
        elif ims is not None:
            t = parse_date(ims)
            if t is not None and mtime <= t:
                raise not_modified

    @staticmethod
    def parse_range(value, size):
        """(start, end), None to ignore (malformed or multi-range: S3 sends the
        whole object) or "unsatisfiable"."""
        m = re.fullmatch(r"\s*bytes\s*=\s*(\d*)\s*-\s*(\d*)\s*", value)
        if not m or (m.group(1) == "" and m.group(2) == ""):
            return None
        a, b = m.group(1), m.group(2)
        if a == "":
            n = int(b)
            if n == 0 or size == 0:
                return "unsatisfiable"
            return max(0, size - n), size - 1
        a = int(a)
        if b != "" and int(b) < a:
            return None
        if a >= size:
            return "unsatisfiable"
        e = size - 1 if b == "" else min(int(b), size - 1)
        return a, e

    # ---------------------------------------------------------------- control
    def send_json(self, status, obj):
        body = (json.dumps(obj, indent=1, sort_keys=True) + "\n").encode()
        self.send_response(status)
        self.send_header("Content-Type", "application/json")
        self.send_header("Content-Length", str(len(body)))
        self.end_headers()
        if self.command != "HEAD":
            self.wfile.write(body)

    def control(self, method, raw_path, raw_query):
        srv = self.server
        try:
            body = self.read_body()
            if raw_path == "/__stats" and method in ("GET", "HEAD"):
                snap = srv.stats.snapshot()
                snap["faults"] = srv.faults.snapshot()
                q = dict(query_pairs(raw_query))
                if q.get("log") in ("0", "false"):
                    snap.pop("log")
                if q.get("reset") in ("1", "true"):
                    srv.stats.reset()
                return self.send_json(200, snap)
            if raw_path == "/__health":
                return self.send_json(200, {"ok": True, "port": srv.server_address[1]})
            if raw_path == "/__control" and method == "POST":
                req = json.loads(body.decode() or "{}")
                ops = req if isinstance(req, list) else [req]
                results = [self.control_op(op) for op in ops]
                return self.send_json(200, {"ok": True, "results": results})
            return self.send_json(404, {"ok": False, "error": "unknown control path"})
        except (ValueError, KeyError, TypeError, OSError) as e:
            return self.send_json(400, {"ok": False, "error": "%s: %s" % (type(e).__name__, e)})

    def control_op(self, op):
        srv = self.server
        name = op.get("op")
        if name == "fault":
            rule = {k: v for k, v in op.items() if k != "op"}
            return {"id": srv.faults.add(rule)}
        if name == "clear_faults":
            srv.faults.clear()
            return {}
        if name == "reset_stats":
            srv.stats.reset()
            return {}
        if name in ("put", "delete"):
            bucket, key = op["bucket"], op["key"]
            bdir = os.path.join(srv.cfg.root, bucket)
            if name == "put":
                os.makedirs(bdir, exist_ok=True)
            full = self.resolve_key(bdir, key)
            if full is None:
                raise ValueError("bad key")
            if name == "delete":
                os.unlink(full)
                return {}
            if "b64" in op:
                data = base64.b64decode(op["b64"])
            else:
                data = op.get("text", "").encode()
            os.makedirs(os.path.dirname(full), exist_ok=True)
            fd, tmp = tempfile.mkstemp(prefix=".s3tmp", dir=os.path.dirname(full))
            with os.fdopen(fd, "wb") as f:
                f.write(data)
            os.replace(tmp, full)
            return {"etag": srv.etags.etag(full, os.stat(full)), "size": len(data)}
        if name == "public":
            srv.public = set(op.get("buckets", []))
            return {}
        if name == "shutdown":
            srv.stopping.set()
            return {}
        raise ValueError("unknown op %r" % name)


def watch_stdin(stop):
    try:
        mode = os.fstat(0).st_mode
    except OSError:
        return
    if not (stat.S_ISFIFO(mode) or stat.S_ISSOCK(mode)):
        return  # /dev/null, a tty or a file: nothing to watch

    def run():
        try:
            while os.read(0, 4096):
                pass
        except OSError:
            pass
        stop.set()
    threading.Thread(target=run, daemon=True).start()


def watch_pid(pid, stop):
    def run():
        while not stop.is_set():
            try:
                os.kill(pid, 0)
            except ProcessLookupError:
                stop.set()
                return
            except PermissionError:
                pass
            time.sleep(0.5)
    threading.Thread(target=run, daemon=True).start()


def main():
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--root", required=True, help="folder: <root>/<bucket>/<key>")
    ap.add_argument("--cred", action="append", default=[],
                    help="KEY:SECRET[:SESSION_TOKEN] accepted (repeatable)")
    ap.add_argument("--public", action="append", default=[],
                    help="bucket that allows anonymous GET/HEAD (repeatable)")
    ap.add_argument("--region", default="us-east-1", help="expected region, '*' = any")
    ap.add_argument("--vhost-suffix", action="append", default=None,
                    help="Host <bucket>.<suffix> is virtual-host style "
                         "(default: s3.localhost and localhost)")
    ap.add_argument("--bind", default="127.0.0.1")
    ap.add_argument("--port", type=int, default=0)
    ap.add_argument("--lifetime", type=float, default=600, help="exit after N seconds")
    ap.add_argument("--parent-pid", type=int, default=0, help="exit when this process is gone")
    ap.add_argument("--port-file", help="also write the port number to this file")
    ap.add_argument("--tls", nargs=2, metavar=("CERT", "KEY"), help="serve HTTPS")
    ap.add_argument("--max-skew", type=float, default=900,
                    help="max |x-amz-date - now| seconds (0 = no check)")
    ap.add_argument("--allow-missing-content-sha256", dest="require_content_sha256",
                    action="store_false", help="do not require x-amz-content-sha256 "
                    "(real S3 requires it on header-signed requests)")
    ap.add_argument("--raw-canonical-uri", action="store_true",
                    help="canonicalize path and query as botocore does for a URL "
                         "(as received, query pairs sorted but not re-encoded) instead "
                         "of S3's decode-and-re-encode")
    ap.add_argument("--fault", action="append", default=[],
                    help="fault rule as JSON (same fields as the control op 'fault')")
    ap.add_argument("--delay-ms", type=int, default=0,
                    help="delay every GET/HEAD by this many ms before the first byte")
    ap.add_argument("--rate-mbit", type=float, default=0,
                    help="send object bodies no faster than this many Mbit/s in all (0: no limit)")
    ap.add_argument("--verbose", "-v", action="store_true")
    cfg = ap.parse_args()
    if cfg.vhost_suffix is None:
        cfg.vhost_suffix = ["s3.localhost", "localhost"]
    cfg.root = os.path.abspath(cfg.root)
    if not os.path.isdir(cfg.root):
        ap.error("--root %s is not a folder" % cfg.root)
    if cfg.bind not in ("127.0.0.1", "::1", "localhost") and not cfg.bind.startswith("127."):
        ap.error("--bind must be a loopback address")

    if ":" in cfg.bind:
        S3Server.address_family = socket.AF_INET6
    srv = S3Server((cfg.bind, cfg.port), Handler, cfg)
    srv.link = LinkLimit(cfg.rate_mbit) if cfg.rate_mbit > 0 else None
    for f in cfg.fault:
        srv.faults.add(json.loads(f))
    if cfg.delay_ms:
        srv.faults.add({"action": "delay", "ms": cfg.delay_ms, "count": -1})
    port = srv.server_address[1]
    if cfg.port_file:
        tmp = cfg.port_file + ".tmp"
        with open(tmp, "w") as fh:
            fh.write("%d\n" % port)
        os.replace(tmp, cfg.port_file)
    sys.stdout.write("PORT %d\n" % port)
    sys.stdout.flush()

    stop = srv.stopping
    watch_stdin(stop)
    if cfg.parent_pid:
        watch_pid(cfg.parent_pid, stop)
    for sig in (signal.SIGTERM, signal.SIGINT, signal.SIGHUP):
        signal.signal(sig, lambda *_: stop.set())
    t = threading.Thread(target=srv.serve_forever, kwargs={"poll_interval": 0.2}, daemon=True)
    t.start()
    stop.wait(cfg.lifetime)
    stop.set()
    srv.shutdown()
    srv.server_close()
    sys.stdout.flush()
    os._exit(0)


if __name__ == "__main__":
    main()

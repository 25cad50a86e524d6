"""The tests' HTTP server: serves a folder with Range, ETag, If-Match and If-None-Match,
as S3 and static file servers do, and injects the faults the remote readers must survive.

    python3 range_server.py FOLDER

binds 127.0.0.1 on a free port, prints the port on stdout and serves until its stdin
closes (the test ends) or it is killed. Control, by GET:

    /_fault?mode=MODE&count=N&skip=K   after K good requests, the next N (default: all)
                                get MODE:
        status:CODE     answer CODE (503, 429, 403, 401...) with no body
        reset           close the connection without an answer
        stall           answer nothing for 60 s
        ignore-range    answer 200 with the whole object to a Range request
        short           a Range answer whose body holds half the range (with a
                        Content-Length to match, and the Content-Range of the whole range)
        truncate        a Range answer that closes the connection halfway through its body
        change          the file as though rewritten: another ETag (If-Match fails: 412)
        redirect:PORT   answer 307 to the same path on 127.0.0.1:PORT (another origin)
        need-query:Q    answer 403 to a request whose query is not Q (a pre-signed URL's)
        weak-etag       a weak ETag (W/"..."), which no If-Match matches (412), as nginx
                        sends for content it may compress
        huge            a Range answer that declares a 2 GiB body (Content-Length
                        2147483648, the Content-Range of the range asked) and sends the
                        range's bytes, then zeros until the client stops reading
    /_stats             {"requests": N, "bytes": N, "ranges": N, "tokens": N,
                        "authorized": N} since the start or /_reset (tokens: requests
                        that carried x-amz-security-token; authorized: Authorization)
    /_reset             zero the counts and clear the fault

A file's ETag is its size and modification time (as nginx makes it), so a file rewritten
while a test reads it is a changed object.
"""

import json
import os
import socket
import sys
import threading
import time
import urllib.parse
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer

ROOT = os.path.abspath(sys.argv[1])
LOCK = threading.Lock()
STATE = {"requests": 0, "bytes": 0, "ranges": 0, "tokens": 0, "authorized": 0, "fault": None,
         "count": 0, "skip": 0}
COUNTS = ("requests", "bytes", "ranges", "tokens", "authorized")


def take_fault():
    with LOCK:
        STATE["requests"] += 1
        mode = STATE["fault"]
        if mode is None:
            return None
        if STATE["skip"] > 0:
            STATE["skip"] -= 1
            return None
        if STATE["count"] > 0:
            STATE["count"] -= 1
            if STATE["count"] == 0:
                STATE["fault"] = None
        return mode


class Handler(BaseHTTPRequestHandler):
    protocol_version = "HTTP/1.1"

    def log_message(self, *args):
        pass

    def setup(self):
        super().setup()
        # Headers and body go out as two writes: without this, Nagle's algorithm and the
        # client's delayed ACK hold every answer back by 40 ms.
        self.connection.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)

    def control(self, url):
        q = urllib.parse.parse_qs(url.query)
        with LOCK:
            if url.path == "/_fault":
                STATE["fault"] = q.get("mode", [None])[0]
                STATE["count"] = int(q.get("count", ["0"])[0])
                STATE["skip"] = int(q.get("skip", ["0"])[0])
            elif url.path == "/_reset":
                STATE.update({k: 0 for k in COUNTS}, fault=None, count=0, skip=0)
            body = json.dumps({k: STATE[k] for k in COUNTS}).encode()
        self.send_response(200)
        self.send_header("Content-Type", "application/json")
        self.send_header("Content-Length", str(len(body)))
        self.end_headers()
        self.wfile.write(body)

    def do_HEAD(self):
        self.serve(head=True)

    def do_GET(self):
        self.serve(head=False)

    def serve(self, head):
        url = urllib.parse.urlparse(self.path)
        if url.path.startswith("/_"):
            return self.control(url)
        with LOCK:
            STATE["tokens"] += int("x-amz-security-token" in self.headers)
            STATE["authorized"] += int("Authorization" in self.headers)
        fault = take_fault()
        if fault and fault.startswith("need-query:") and url.query != fault.split(":", 1)[1]:
            self.send_response(403)
            self.send_header("Content-Length", "0")
            self.end_headers()
            return
        if fault and fault.startswith("redirect:"):
            self.send_response(307)
            self.send_header("Location", "http://127.0.0.1:%s%s" % (fault.split(":")[1], self.path))
            self.send_header("Content-Length", "0")
            self.end_headers()
            return
        if fault == "reset":
            self.close_connection = True
            self.connection.shutdown(2)
            return
        if fault == "stall":
            time.sleep(60)
            return
        if fault and fault.startswith("status:"):
            self.send_response(int(fault.split(":")[1]))
            self.send_header("Content-Length", "0")
            self.end_headers()
            return
        path = os.path.normpath(os.path.join(ROOT, urllib.parse.unquote(url.path).lstrip("/")))
        if not path.startswith(ROOT) or not os.path.isfile(path):
            self.send_response(404)
            self.send_header("Content-Length", "0")
            self.end_headers()
            return
        st = os.stat(path)
        size = st.st_size
        etag = '"%x-%x"' % (st.st_mtime_ns, size)
        if fault == "change":
            etag = '"changed-%x"' % size
        if fault == "weak-etag":
            etag = "W/" + etag
        if self.headers.get("If-None-Match") == etag:
            self.send_response(304)
            self.send_header("ETag", etag)
            self.end_headers()
            return
        match = self.headers.get("If-Match")
        # Strong comparison: a weak ETag on either side never matches.
        if match is not None and (match != etag or etag.startswith("W/")):
            self.send_response(412)
            self.send_header("Content-Length", "0")
            self.end_headers()
            return
        rng = self.headers.get("Range")
        start, end = 0, size
        partial = False
        if rng and fault != "ignore-range":
            a, b = rng.split("=", 1)[1].split("-", 1)
            start = int(a)
            end = min(int(b) + 1, size) if b else size
            if start >= size:
                self.send_response(416)
                self.send_header("Content-Range", "bytes */%d" % size)
                self.send_header("Content-Length", "0")
                self.end_headers()
                return
            partial = True
        with open(path, "rb") as f:
            f.seek(start)
            body = f.read(end - start)
        sent = body
        if partial and fault == "short":
            sent = body[: len(body) // 2]
        self.send_response(206 if partial else 200)
        self.send_header("ETag", etag)
        self.send_header(
            "Last-Modified", time.strftime("%a, %d %b %Y %H:%M:%S GMT", time.gmtime(st.st_mtime))
        )
        self.send_header("Accept-Ranges", "bytes")
        if partial:
            self.send_header("Content-Range", "bytes %d-%d/%d" % (start, end - 1, size))
        huge = partial and fault == "huge"
        self.send_header("Content-Length", str(2**31 if huge else len(sent)))
        self.end_headers()
        if head:
            return
        if huge:
            try:
                self.wfile.write(sent)
                for _ in range(2**31 // 65536):
                    self.wfile.write(bytes(65536))
            except (BrokenPipeError, ConnectionResetError):
                pass
            self.close_connection = True
            return
        if partial and fault == "truncate":
            sent = sent[: len(sent) // 2]
            self.close_connection = True
        try:
            self.wfile.write(sent)
        except (BrokenPipeError, ConnectionResetError):
            return
        with LOCK:
            STATE["bytes"] += len(sent)
            STATE["ranges"] += int(partial)
        if fault == "truncate":
            self.connection.shutdown(2)


def main():
    server = ThreadingHTTPServer(("127.0.0.1", 0), Handler)
    server.daemon_threads = True
    if len(sys.argv) > 2:
        # HTTPS with the certificate and key in this PEM file (the tests' self-signed one,
        # which no client trusts: a bad certificate).
        import ssl
        context = ssl.SSLContext(ssl.PROTOCOL_TLS_SERVER)
        context.load_cert_chain(sys.argv[2])
        server.socket = context.wrap_socket(server.socket, server_side=True)
    print(server.server_address[1], flush=True)
    threading.Thread(target=server.serve_forever, daemon=True).start()
    # Serve until the test closes our stdin (or dies): no server outlives its test.
    sys.stdin.read()
    server.shutdown()


if __name__ == "__main__":
    main()

#!/usr/bin/env python3
"""Streams a hapsyn-motion recording (CSV) to `hapsyn view`'s live prototype at real time, as a
tracker bridge would: one message per row over the WebSocket ws://HOST:PORT/live,

    {"t": seconds, "position": [x, y, z], "orientation": [w, x, y, z]}

and prints the frames the server answers (joint angles, the largest |qdot|/limit and |tau|/limit,
feasibility). The page (`hapsyn view STUDY`, button "live") shows the arm following the stream.
Standard library only (a minimal WebSocket client: RFC 6455, text frames, masked).

Usage: stream_recording.py URL RECORDING.csv [--speed X] [--every N] [--quiet]
  URL: what `hapsyn view` printed, e.g. http://127.0.0.1:8080/
"""
import argparse
import base64
import csv
import json
import os
import socket
import struct
import sys
import time
import urllib.parse


class WebSocket:
    """A minimal blocking WebSocket client: connect, send text, receive text."""

    def __init__(self, url, timeout=10.0):
        parts = urllib.parse.urlsplit(url)
        if parts.scheme != "ws":
            raise ValueError(f"{url}: only ws:// URLs")
        self.sock = socket.create_connection((parts.hostname, parts.port or 80), timeout=timeout)
        key = base64.b64encode(os.urandom(16)).decode()
        host = parts.netloc
        request = (f"GET {parts.path or '/'} HTTP/1.1\r\nHost: {host}\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n"
                   f"Sec-WebSocket-Key: {key}\r\nSec-WebSocket-Version: 13\r\n\r\n")
        self.sock.sendall(request.encode())
        head = b""
        while b"\r\n\r\n" not in head:
            chunk = self.sock.recv(4096)
            if not chunk:
                raise ConnectionError("the server closed the connection during the handshake")
            head += chunk
        head, self.pending = head.split(b"\r\n\r\n", 1)
        status = head.split(b"\r\n", 1)[0].decode()
        if " 101 " not in status + " ":
            raise ConnectionError(f"handshake refused: {status}")

    def _read(self, n):
        while len(self.pending) < n:
            chunk = self.sock.recv(65536)
            if not chunk:
                raise ConnectionError("the server closed the connection")
            self.pending += chunk
        data, self.pending = self.pending[:n], self.pending[n:]
        return data

    def send_frame(self, opcode, payload):
        header = bytes([0x80 | opcode])
        n = len(payload)
        if n < 126:
            header += bytes([0x80 | n])
        elif n < 1 << 16:
            header += bytes([0x80 | 126]) + struct.pack("!H", n)
        else:
            header += bytes([0x80 | 127]) + struct.pack("!Q", n)
        mask = os.urandom(4)
        self.sock.sendall(header + mask + bytes(b ^ mask[i % 4] for i, b in enumerate(payload)))

    def send(self, text):
        self.send_frame(0x1, text.encode())

    def receive(self):
        """The next text message (str); raises ConnectionError when the server closes."""
        message = b""
        while True:
            b0, b1 = self._read(2)
            opcode, n = b0 & 0x0F, b1 & 0x7F
            if n == 126:
                n = struct.unpack("!H", self._read(2))[0]
            elif n == 127:
                n = struct.unpack("!Q", self._read(8))[0]
            payload = self._read(n)
            if opcode == 0x8:
                code = struct.unpack("!H", payload[:2])[0] if len(payload) >= 2 else None
                raise ConnectionError(f"the server closed the connection (code {code})")
            if opcode == 0x9:  # ping
                self.send_frame(0xA, payload)
                continue
            if opcode in (0x1, 0x0, 0x2):
                message += payload
                if b0 & 0x80:
                    return message.decode()

    def close(self):
        try:
            self.send_frame(0x8, struct.pack("!H", 1000))
        finally:
            self.sock.close()


def live_url(url):
    """ws://HOST:PORT/live from the page's http://HOST:PORT/ URL."""
    parts = urllib.parse.urlsplit(url)
    return f"ws://{parts.netloc}/live"


def read_recording(path):
    """Rows of a hapsyn-motion CSV as (t, position, orientation); quaternion or matrix columns."""
    with open(path, newline="") as f:
        lines = [line for line in f if not line.startswith("#")]
    rows = list(csv.DictReader(lines))
    poses = []
    for r in rows:
        if "qw" in r:
            orientation = [float(r[k]) for k in ("qw", "qx", "qy", "qz")]
        else:
            orientation = [[float(r[f"r{i}{j}"]) for j in (1, 2, 3)] for i in (1, 2, 3)]
        poses.append((float(r["time"]), [float(r[k]) for k in ("x", "y", "z")], orientation))
    return poses


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("url", help="the URL hapsyn view printed, e.g. http://127.0.0.1:8080/")
    parser.add_argument("recording", help="a hapsyn-motion CSV (unit m, time in s)")
    parser.add_argument("--speed", type=float, default=1.0, help="playback speed (1 = real time)")
    parser.add_argument("--every", type=int, default=30, help="print every N-th frame")
    parser.add_argument("--quiet", action="store_true", help="print only the summary")
    args = parser.parse_args()
    poses = read_recording(args.recording)
    ws = WebSocket(live_url(args.url))
    start, t0 = time.monotonic(), poses[0][0]
    infeasible = errors = 0
    for k, (t, position, orientation) in enumerate(poses):
        delay = (t - t0) / args.speed - (time.monotonic() - start)
        if delay > 0:
            time.sleep(delay)
        ws.send(json.dumps({"t": t, "position": position, "orientation": orientation}))
        frame = json.loads(ws.receive())
        if "error" in frame:
            errors += 1
            print(f"t = {t:.3f} s: {frame['error']}", file=sys.stderr)
            continue
        infeasible += frame["feasible"] == 0
        if not args.quiet and k % args.every == 0:
            q = frame["q"]
            worst = [max(v) if v else None for v in (frame["qdot_ratio"], frame["tau_ratio"])]
            print(f"t = {t:7.3f} s  {frame['status']:11s} q = {['%.3f' % v for v in q] if q else None}"
                  f"  max |qdot|/limit = {worst[0]}  max |tau|/limit = {worst[1]}  feasible = {frame['feasible']}")
    ws.close()
    print(f"{len(poses)} poses streamed in {time.monotonic() - start:.1f} s; {infeasible} frames infeasible, {errors} errors")
    return 1 if errors else 0


if __name__ == "__main__":
    sys.exit(main())

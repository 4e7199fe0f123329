"""Starts `hapsyn view` for a test and stops it: the URL it prints, its output, its exit code."""
import re
import signal
import subprocess
import threading
import time

URL = re.compile(r"hapsyn view: serving (\S*) at (http://[^/\s]+/)")


class ViewProcess:
    """`hapsyn view ARGS... --port 0` running until stop(); url is what it printed."""

    def __init__(self, hapsyn, *args, timeout=120):
        self.process = subprocess.Popen([hapsyn, "view", *args, "--port", "0"], stdout=subprocess.PIPE,
                                        stderr=subprocess.PIPE, text=True)
        self.stderr = []  # every line of stderr, read by one thread (complete after stop())
        self._stderr_reader = threading.Thread(target=lambda: self.stderr.extend(self.process.stderr), daemon=True)
        self._stderr_reader.start()
        self.url, self.study = None, None
        deadline = time.time() + timeout
        for line in self.process.stdout:
            match = URL.search(line)
            if match:
                self.study, self.url = match.group(1), match.group(2)
                break
            if time.time() > deadline:
                break
        if self.url is None:
            self.process.kill()
            raise RuntimeError("hapsyn view printed no URL; stderr:\n" + "".join(self.stderr))
        self.port = int(self.url.rsplit(":", 1)[1].strip("/"))

    def stop(self, sig=signal.SIGINT, timeout=10):
        """Sends `sig`; returns (exit code, the rest of stdout) once the process has ended and
        self.stderr holds all it wrote. (Not communicate(): it would read stderr too, taking
        lines from the reader thread.)"""
        self.process.send_signal(sig)
        self.process.wait(timeout=timeout)  # hapsyn view writes little: no pipe fills up meanwhile
        rest = self.process.stdout.read()
        self._stderr_reader.join(timeout)
        return self.process.returncode, rest

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        if self.process.poll() is None:
            self.process.kill()
            self.process.wait()


def read_csv_columns(path):
    """samples.csv as {column: [cells]} and its row count."""
    import csv
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    header, body = rows[0], rows[1:]
    return {name: [r[k] for r in body] for k, name in enumerate(header)}, len(body)

"""Running nerfpt as a child process: its output read line by line while it runs, and a cancel that leaves
nothing behind (the child is terminated and waited for; nerfpt finishes a file it is writing first, and writes
files to a temporary name that it renames, so no half-written file remains).

Pure Python (no bpy). Blender's render thread and its modal operators both poll a ChildProcess; the tests use
it directly.
"""

import os
import queue
import subprocess
import threading
import time

from . import nerfpt_cli


class ChildProcess:
    """One running command. Lines from stdout and stderr are collected by two reader threads; poll() hands
    over the new ones. Use as a context manager: leaving the block cancels a child that still runs."""

    def __init__(self, cmd, env=None):
        self.cmd = list(cmd)
        self.stdout_lines = []
        self.lines = []  # every (stream, line) in the order poll() took them
        self.stderr_lines = []
        self.progress = 0.0
        self.cancelled = False
        self._queue = queue.Queue()
        try:
            self._proc = subprocess.Popen(
                self.cmd,
                stdin=subprocess.DEVNULL,
                stdout=subprocess.PIPE,
                stderr=subprocess.PIPE,
                text=True,
                errors="replace",
                bufsize=1,
                env=env,
            )
        except OSError as e:
            raise nerfpt_cli.NerfptError(f"cannot start '{self.cmd[0]}': {e.strerror or e}") from None
        self.pid = self._proc.pid
        self._readers = [
            threading.Thread(target=self._read, args=(self._proc.stdout, "out"), daemon=True),
            threading.Thread(target=self._read, args=(self._proc.stderr, "err"), daemon=True),
        ]
        for t in self._readers:
            t.start()

    def _read(self, stream, name):
        for line in stream:
            self._queue.put((name, line.rstrip("\r\n")))
        stream.close()

    def poll(self):
        """New (stream, line) pairs since the last call ('out' or 'err'); updates progress."""
        new = []
        while True:
            try:
                name, line = self._queue.get_nowait()
            except queue.Empty:
                break
            (self.stdout_lines if name == "out" else self.stderr_lines).append(line)
            self.lines.append((name, line))
            if name == "err":
                f = nerfpt_cli.progress_fraction(line)
                if f is not None:
                    self.progress = f
            new.append((name, line))
        return new

    def running(self):
        return self._proc.poll() is None

    @property
    def returncode(self):
        return self._proc.returncode

    def finish(self):
        """Waits for the child and its output; returns the exit code."""
        self._proc.wait()
        for t in self._readers:
            t.join()
        self.poll()
        return self._proc.returncode

    def cancel(self, grace_s=10.0):
        """Stops the child: SIGTERM (nerfpt completes a file being written, then exits), SIGKILL after grace_s."""
        if self._proc.poll() is None:
            self.cancelled = True
            self._proc.terminate()
            try:
                self._proc.wait(timeout=grace_s)
            except subprocess.TimeoutExpired:
                self._proc.kill()
        self.finish()

    def failure(self):
        return nerfpt_cli.failure_message(self.stderr_lines, self._proc.returncode)

    def warnings(self):
        return [w for w in (nerfpt_cli.warning_message(ln) for ln in self.stderr_lines) if w]

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.cancel()
        return False


def run(cmd, should_cancel=lambda child: False, on_line=None, poll_s=0.05, env=None):
    """Runs cmd to the end or until should_cancel(child) is true; on_line(child, stream, line) sees every line.
    Returns the finished ChildProcess (check .cancelled and .returncode)."""
    delivered = 0

    def deliver():
        # From child.lines, not poll()'s result: finish() and cancel() also poll, and the lines they take
        # (the last ones, often the error) must reach on_line too.
        nonlocal delivered
        child.poll()
        if on_line:
            for name, line in child.lines[delivered:]:
                on_line(child, name, line)
        delivered = len(child.lines)

    with ChildProcess(cmd, env=env) as child:
        while True:
            deliver()
            if not child.running():
                break
            if should_cancel(child):
                child.cancel()
                break
            time.sleep(poll_s)
        child.finish()
        deliver()
    return child


def process_exists(pid):
    """True while a process with this id exists and is not a zombie (for the tests' 'nothing left' checks)."""
    try:
        with open(f"/proc/{pid}/stat") as f:
            state = f.read().rsplit(")", 1)[1].split()[0]
        return state != "Z"
    except (FileNotFoundError, ProcessLookupError, IndexError):
        return False
    except OSError:
        try:
            os.kill(pid, 0)
            return True
        except OSError:
            return False

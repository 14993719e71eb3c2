"""The command line as a user runs it, for the tests: ``python -m hexapod ARGS`` in a fresh
process, with the test session's environment (its cache folder, one BLAS thread: see
``conftest.py``) less ``HEXAPOD_DEBUG`` (a user's error is one line, not a traceback), a time
limit and its output captured as text.

:func:`hexapod` runs a command to its end; :func:`python` runs any ``python ARGS`` the same way
(``-X importtime -m hexapod ...``, ``-c CODE``) and :func:`run` any program; :class:`Running`
starts ``python ARGS`` in the background and reads its output as it comes, so that a test can
wait for what the run announces before it acts (never a fixed sleep, which a loaded machine
outlasts): a progress line (``HEXAPOD_PROGRESS=1`` draws them on a pipe too), or the signal
handlers the command installs first.

:func:`in_process` runs the command by its entry function in the test's own process, for the
tests that are about what a command does rather than about the process (its exit on a signal,
its imports, the environment it starts with): the status is the one the process would end with
(``python -m hexapod`` exits with what the entry function returns), and stdout and stderr are
read at their descriptors, so what a compiled library writes there is seen as from a process.
It saves the second or so each process spends importing NumPy, SciPy, CasADi and Matplotlib.
"""

from __future__ import annotations

import io
import os
import subprocess
import sys
import tempfile
import threading
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path

#: Seconds a command of the tests may take: far more than any needs on an idle machine (a few
#: seconds), so that a loaded one does not fail them.
TIMEOUT = 300.0
#: Seconds a test waits for what a run announces: far more than it takes on an idle machine
#: (under a second to a few seconds).
ANNOUNCE = 60.0
#: How often (s) a waiting test looks again.
POLL = 0.02


def environment(**settings: str | None) -> dict[str, str]:
    """The test session's environment less ``HEXAPOD_DEBUG``, with ``settings`` (a variable
    set to None is removed)."""
    env = {k: v for k, v in os.environ.items() if k != "HEXAPOD_DEBUG"}
    for name, value in settings.items():
        if value is None:
            env.pop(name, None)
        else:
            env[name] = value
    return env


def run(argv: list[str], cwd: Path, timeout: float = TIMEOUT,
        **settings: str | None) -> subprocess.CompletedProcess:
    """The program ``argv`` run to its end from ``cwd`` (the test's own folder: a command
    writes there), with the session's environment and ``settings`` (environment variables),
    its stdout and stderr captured as text."""
    return subprocess.run(argv, cwd=cwd, env=environment(**settings), capture_output=True,
                          text=True, timeout=timeout)


def python(*args: str, cwd: Path, timeout: float = TIMEOUT,
           **settings: str | None) -> subprocess.CompletedProcess:
    """``python ARGS`` run to its end from ``cwd``, as :func:`run`."""
    return run([sys.executable, *args], cwd, timeout, **settings)


def hexapod(*args: str, cwd: Path, timeout: float = TIMEOUT,
            **settings: str | None) -> subprocess.CompletedProcess:
    """``python -m hexapod ARGS`` run to its end from ``cwd``, as :func:`python`."""
    return python("-m", "hexapod", *args, cwd=cwd, timeout=timeout, **settings)


def in_process(*args: str, cwd: Path, **settings: str | None) -> subprocess.CompletedProcess:
    """``hexapod ARGS`` run to its end by the entry function in this process, from ``cwd`` and
    with the session's environment less ``HEXAPOD_DEBUG`` and with ``settings``, as
    :func:`hexapod` runs it in a process of its own (both restored afterwards): its status, and
    what it wrote on stdout and stderr as text. A ``SystemExit`` (a usage error, which argparse
    ends by exiting) is the status it carries, as for a process."""
    from hexapod.cli import main

    with _environment(cwd, environment(**settings)), _captured() as output:
        try:
            status = main(list(args))
        except SystemExit as ended:
            status = ended.code if isinstance(ended.code, int) else int(ended.code is not None)
    return subprocess.CompletedProcess(["hexapod", *args], status, *output)


@contextmanager
def _environment(cwd: Path, env: dict[str, str]) -> Iterator[None]:
    """Work in ``cwd`` with exactly the variables ``env``; the earlier ones restored after."""
    before_env, before_cwd = dict(os.environ), os.getcwd()
    os.environ.clear()
    os.environ.update(env)
    os.chdir(cwd)
    try:
        yield
    finally:
        os.chdir(before_cwd)
        os.environ.clear()
        os.environ.update(before_env)


@contextmanager
def _captured() -> Iterator[list[str]]:
    """Capture stdout and stderr at their descriptors and at ``sys.stdout``/``sys.stderr``
    (each stream one file, shared by both, so that their writes keep their order); the list
    yielded holds the two texts once the block ends."""
    output: list[str] = []
    saved = []
    for number, name in ((1, "stdout"), (2, "stderr")):
        getattr(sys, name).flush()
        file = tempfile.TemporaryFile()
        saved.append((number, name, getattr(sys, name), os.dup(number), file))
        os.dup2(file.fileno(), number)
        setattr(sys, name, io.TextIOWrapper(open(file.fileno(), "wb", closefd=False),
                                            encoding="utf-8", errors="replace",
                                            write_through=True))
    try:
        yield output
    finally:
        for number, name, stream, descriptor, file in saved:
            getattr(sys, name).flush()
            setattr(sys, name, stream)
            os.dup2(descriptor, number)
            os.close(descriptor)
            file.seek(0)
            output.append(file.read().decode("utf-8", errors="replace"))
            file.close()


class Running:
    """``python ARGS`` started in the background from ``cwd``, its stdout and stderr read as
    they come (a thread each). A context manager: a run still going at the end of the block is
    killed.

    ``default_sigint``: the child takes the default action for SIGINT, whatever the test's
    process does (a shell that starts a job in the background, ``nohup ... &``, makes it ignore
    SIGINT, and Python then never turns SIGINT into KeyboardInterrupt).
    """

    def __init__(self, *args: str, cwd: Path, default_sigint: bool = False,
                 **settings: str | None):
        import signal

        def default() -> None:
            signal.signal(signal.SIGINT, signal.SIG_DFL)

        self.process = subprocess.Popen(
            [sys.executable, *args], cwd=cwd, env=environment(**settings),
            stdout=subprocess.PIPE, stderr=subprocess.PIPE,
            preexec_fn=default if default_sigint else None)
        self._text = {"stdout": [], "stderr": []}
        self._lock = threading.Lock()
        self._readers = [threading.Thread(target=self._read, args=(name,), daemon=True)
                         for name in self._text]
        for reader in self._readers:
            reader.start()

    def _read(self, name: str) -> None:
        stream = getattr(self.process, name)
        while chunk := os.read(stream.fileno(), 65536):
            with self._lock:
                self._text[name].append(chunk)

    def output(self, name: str = "stderr") -> str:
        """What the run has written on ``name`` (stdout or stderr) so far."""
        with self._lock:
            return b"".join(self._text[name]).decode(errors="replace")

    def wait_until(self, condition: Callable[[str], bool], what: str,
                   timeout: float = ANNOUNCE) -> None:
        """Return once ``condition(stderr so far)`` holds; fail (AssertionError, with the
        run's stderr) if the run ends first or ``timeout`` seconds pass. ``what`` names the
        awaited event in that message."""
        deadline = time.monotonic() + timeout
        while not condition(self.output()):
            if self.process.poll() is not None:
                for reader in self._readers:  # what was left in the pipes
                    reader.join(timeout=10)
                if condition(self.output()):
                    return
                raise AssertionError(f"the run ended ({self.process.returncode}) before "
                                     f"{what}:\n{self.output()}")
            if time.monotonic() > deadline:
                raise AssertionError(f"not {what} within {timeout:g} s:\n{self.output()}")
            time.sleep(POLL)

    def wait_for(self, text: str, timeout: float = ANNOUNCE) -> None:
        """Return once ``text`` is on the run's stderr (see :meth:`wait_until`)."""
        self.wait_until(lambda err: text in err, f"writing {text!r}", timeout)

    def wait_for_handler(self, number: int, timeout: float = ANNOUNCE) -> None:
        """Return once the run catches signal ``number`` (``/proc/PID/status``, Linux): the
        command installs its handlers of SIGINT and SIGTERM before anything else, so a
        signal sent then finds it in its imports. Where the system does not say, once the run
        writes on stderr (``HEXAPOD_PROGRESS=1``: its first progress line)."""
        status = Path(f"/proc/{self.process.pid}/status")
        if not status.exists():
            self.wait_until(bool, "writing on stderr", timeout)
            return

        def caught(_: str) -> bool:
            try:
                lines = status.read_text().splitlines()
            except OSError:  # the process has ended: wait_until says so
                return False
            mask = next(int(line.split()[1], 16) for line in lines if line.startswith("SigCgt:"))
            return bool(mask >> (number - 1) & 1)
        self.wait_until(caught, f"catching signal {number}", timeout)

    def send_signal(self, number: int) -> None:
        self.process.send_signal(number)

    def finish(self, timeout: float = TIMEOUT) -> tuple[int, str, str]:
        """Wait for the end of the run: its status, stdout and stderr."""
        self.process.wait(timeout=timeout)
        for reader in self._readers:
            reader.join(timeout=timeout)
        return self.process.returncode, self.output("stdout"), self.output("stderr")

    def __enter__(self) -> Running:
        return self

    def __exit__(self, *exc) -> None:
        if self.process.poll() is None:  # never leave a run behind
            self.process.kill()
        self.process.wait()
        for reader in self._readers:
            reader.join(timeout=10)
        for stream in (self.process.stdout, self.process.stderr):
            stream.close()

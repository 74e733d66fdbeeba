"""Start and stop a wsgemu daemon from Python, for tests and scripts.

``Emulator`` runs the daemon on free loopback ports (``--tcp 127.0.0.1:0
--control 127.0.0.1:0`` plus any extra arguments, and ``--script`` for a
startup script), waits for the one ``ready ...`` line it prints on stdout
once every interface is open, and hands out connected clients. ``stop()``
ends it with SIGTERM, after which a healthy daemon exits 0; anything else
(a crash, a sanitizer's abort) is reported with what the daemon wrote on
stderr. With ``comm_log=True`` the daemon also writes its communication
log (``--log``) to a temporary file, which ``comm_log_text()`` reads; with
``udp=True`` it serves UDP on a free port and answers to a free port.
``AttachedEmulator`` gives the same clients for a daemon that runs
already (a CI service container), started and stopped by someone else.
The pytest fixture in ``wsgemu.plugin`` is a thin layer over these
classes.
"""

import os
import selectors
import socket
import shlex
import shutil
import signal
import subprocess
import tempfile
import threading
import time
from types import TracebackType
from typing import IO, Any, Dict, List, Optional, Sequence, Tuple, Type, Union

from .client import Control, Gripper

__all__ = ["AttachedEmulator", "DaemonError", "Emulator", "bundled_binary",
           "find_binary", "free_udp_port", "parse_attach",
           "parse_ready_line"]

# Where the platform wheel (scripts/wheel.sh) puts the static wsgemu and
# wsgctl: inside the package, so installing the wheel installs them.
BUNDLED_DIR = os.path.join(os.path.dirname(os.path.abspath(__file__)), "bin")


class DaemonError(RuntimeError):
    """The daemon could not be found, did not start, or did not end well."""


def bundled_binary(name: str = "wsgemu") -> Optional[str]:
    """The program the platform wheel brought (wsgemu or wsgctl), or None
    when the package was installed without one."""
    path = os.path.join(BUNDLED_DIR, name)
    return path if os.access(path, os.X_OK) else None


def find_binary(path: Optional[str] = None) -> str:
    """The daemon to run: path if given, else $WSGEMU, else the one the
    platform wheel bundled, else wsgemu on PATH. What is asked for by
    name comes first; the bundled one before PATH, so the wheel's daemon
    matches its client even where another wsgemu is installed."""
    candidate = (path or os.environ.get("WSGEMU") or bundled_binary()
                 or shutil.which("wsgemu"))
    if not candidate:
        raise DaemonError("no wsgemu binary: give its path (pytest "
                          "--wsgemu=PATH, or the WSGEMU environment "
                          "variable) or put wsgemu on PATH")
    if not (os.path.isfile(candidate) and os.access(candidate, os.X_OK)):
        raise DaemonError("wsgemu binary %r is not an executable file"
                          % candidate)
    # Absolute, so a later change of directory (pytester does one) does
    # not lose it.
    return os.path.abspath(candidate)


def _hostport(text: str) -> Tuple[str, int]:
    host, _, port = text.rpartition(":")
    return host, int(port)


def free_udp_port(host: str = "127.0.0.1") -> int:
    """A UDP port free on host now: bound as port 0, the kernel's choice.
    For the daemon's answer port, so that parallel test runs (pytest-xdist,
    two CI jobs on one machine) do not all want 1501. Between this and the
    client's bind another program could take it; that window is short."""
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        s.bind((host, 0))
        port: int = s.getsockname()[1]
        return port


def parse_attach(spec: str) -> Tuple[Tuple[str, int],
                                     Optional[Tuple[str, int]]]:
    """The addresses of a daemon to attach to: "HOST:PORT" (its TCP
    interface), optionally followed by ",control=HOST:PORT" (its control
    channel)."""
    first, *rest = spec.split(",")
    try:
        tcp = _hostport(first.strip())
        control = None
        for part in rest:
            key, sep, value = part.strip().partition("=")
            if key != "control" or not sep:
                raise ValueError(part)
            control = _hostport(value)
    except ValueError:
        raise DaemonError("bad attach address %r: HOST:PORT or "
                          "HOST:PORT,control=HOST:PORT" % spec) from None
    return tcp, control


def parse_ready_line(line: str) -> Dict[str, str]:
    """The fields of a ready line: "ready tcp=H:P control=H:P" gives
    {"tcp": "H:P", "control": "H:P"}."""
    words = line.split()
    if not words or words[0] != "ready":
        raise DaemonError("not a ready line: %r" % line)
    fields = {}
    for w in words[1:]:
        key, sep, value = w.partition("=")
        if not sep:
            raise DaemonError("bad field %r in ready line %r" % (w, line))
        fields[key] = value
    return fields


class _Clients:
    """The clients of a daemon, given its addresses: what Emulator and
    AttachedEmulator share. ``tcp`` (list of (host, port), one per gripper
    of a fleet), ``udp`` (list of (host, port, answer_port)),
    ``control_addr``; ``gripper`` and ``control`` connect on first use,
    new_gripper(), new_udp_gripper() and new_control() connect more, and
    close_clients() closes them all."""

    def __init__(self) -> None:
        self.tcp: List[Tuple[str, int]] = []
        self.udp: List[Tuple[str, int, int]] = []
        self.pty: List[str] = []
        self.control_addr: Optional[Tuple[str, int]] = None
        self._clients: List[Union[Gripper, Control]] = []
        self._gripper: Optional[Gripper] = None
        self._control: Optional[Control] = None

    def close_clients(self) -> None:
        """Close every client handed out (grippers announce it with 07h)."""
        for c in reversed(self._clients):
            try:
                c.close()
            except OSError:
                pass
        self._clients.clear()
        self._gripper = None
        self._control = None

    def stderr_text(self) -> str:
        """What the daemon wrote on stderr so far ("" when unknown)."""
        return ""

    def comm_log_text(self) -> str:
        """The daemon's communication log so far ("" when not kept)."""
        return ""

    @property
    def tcp_addr(self) -> Tuple[str, int]:
        if not self.tcp:
            raise DaemonError("the daemon serves no TCP interface")
        return self.tcp[0]

    def new_gripper(self, index: int = 0, **kwargs: Any) -> Gripper:
        """A new TCP client of gripper index (of a fleet), closed by
        close_clients(). kwargs go to Gripper (timeout, motion_timeout)."""
        if not self.tcp:
            raise DaemonError("the daemon serves no TCP interface")
        g = Gripper(self.tcp[index], **kwargs)
        self._clients.append(g)
        return g

    def new_udp_gripper(self, index: int = 0, **kwargs: Any) -> Gripper:
        """A new UDP client of gripper index: it receives on the port the
        daemon answers to (one such client per gripper at a time)."""
        if not self.udp:
            raise DaemonError("the daemon serves no UDP interface: give it "
                              "--udp ADDR:PORT:REMOTE")
        host, port, remote = self.udp[index]
        g = Gripper((host, port), transport="udp", answer_port=remote,
                    **kwargs)
        self._clients.append(g)
        return g

    def new_control(self, **kwargs: Any) -> Control:
        """A new control channel client, closed by close_clients()."""
        if self.control_addr is None:
            raise DaemonError("the daemon serves no control channel")
        c = Control(self.control_addr, **kwargs)
        self._clients.append(c)
        return c

    @property
    def gripper(self) -> Gripper:
        """A TCP client of the (first) gripper, connected on first use."""
        if self._gripper is None or self._gripper.closed:
            self._gripper = self.new_gripper()
        return self._gripper

    @property
    def control(self) -> Control:
        """A control channel client, connected on first use."""
        if self._control is None:
            self._control = self.new_control()
        return self._control


class AttachedEmulator(_Clients):
    """The clients of a daemon that runs already, started by someone else
    (a CI service container): the same client API as Emulator, no process.
    ``tcp``: its TCP interface; ``control``: its control channel, or None.
    stop() closes the clients and leaves the daemon running."""

    def __init__(self, tcp: Union[str, Tuple[str, int]],
                 control: Union[None, str, Tuple[str, int]] = None):
        super().__init__()
        self.tcp = [tcp if isinstance(tcp, tuple) else _hostport(tcp)]
        if control is not None:
            self.control_addr = (control if isinstance(control, tuple)
                                 else _hostport(control))
        self.process: Optional["subprocess.Popen[bytes]"] = None
        self.script: Optional[str] = None

    @classmethod
    def from_spec(cls, spec: str) -> "AttachedEmulator":
        """From "HOST:PORT[,control=HOST:PORT]" (parse_attach)."""
        tcp, control = parse_attach(spec)
        return cls(tcp, control)

    def __enter__(self) -> "AttachedEmulator":
        return self

    def __exit__(self, exc_type: Optional[Type[BaseException]],
                 exc: Optional[BaseException],
                 tb: Optional[TracebackType]) -> None:
        self.stop()

    @property
    def running(self) -> bool:
        return True

    def stop(self, timeout: float = 10.0) -> int:
        """Close the clients; the daemon is not this object's to stop."""
        self.close_clients()
        return 0


class Emulator(_Clients):
    """One wsgemu process and the clients connected to it.

    After start(): ``ready_line`` (as printed), ``fields`` (its key=value
    fields), ``tcp`` (the list of (host, port), one per gripper of a
    fleet), ``tcp_addr`` (the first), ``control_addr``, ``udp`` (list of
    (host, port, answer_port)) and ``pty`` (list of paths) when given, and
    ``process`` (the subprocess.Popen).

    ``gripper`` and ``control`` are clients connected on first use and
    closed by stop(); new_gripper() and new_control() connect more.

    ``script``: a Lua script the daemon runs at its start (``--script``,
    on every gripper of a fleet), its path made absolute here; None for
    none. A script that cannot be read makes start() fail; one that fails
    while it starts leaves the daemon running with SF_SCRIPT_FAILURE set
    (``control.script_status()`` has its error).

    ``udp=True``: the daemon also serves UDP on a free loopback port and
    answers to another free port (free_udp_port), not the fixed 1501.
    ``comm_log=True``: the daemon writes its communication log (``--log``)
    to a temporary file; comm_log_text() reads it.
    ``capture=True``: the daemon captures every interface's traffic as
    pcapng (``--capture``) to a temporary file, ``capture_path`` while it
    runs (save_capture() copies it); removed when the daemon stops.
    """

    def __init__(self, binary: Optional[str] = None,
                 args: Sequence[str] = (), ready_timeout: float = 10.0,
                 interfaces: Sequence[str] = ("--tcp", "127.0.0.1:0",
                                              "--control", "127.0.0.1:0"),
                 script: Optional[Union[str, "os.PathLike[str]"]] = None,
                 udp: bool = False, comm_log: bool = False,
                 capture: bool = False):
        super().__init__()
        self.binary = find_binary(binary)
        self.script = (None if script is None
                       else os.path.abspath(os.fspath(script)))
        self.argv = [self.binary, *interfaces]
        if udp:
            self.argv += ["--udp", "127.0.0.1:0:%d" % free_udp_port()]
        self._log: Optional[str] = None
        if comm_log:
            fd, self._log = tempfile.mkstemp(prefix="wsgemu-log-")
            os.close(fd)
            self.argv += ["--log", self._log]
        self.capture_path: Optional[str] = None
        if capture:
            fd, self.capture_path = tempfile.mkstemp(prefix="wsgemu-",
                                                     suffix=".pcapng")
            os.close(fd)
            self.argv += ["--capture", self.capture_path]
        self.argv += args
        if self.script is not None:
            self.argv += ["--script", self.script]
        self.ready_timeout = ready_timeout
        self.process: Optional["subprocess.Popen[bytes]"] = None
        self.ready_line = ""
        self.fields: Dict[str, str] = {}
        self._stderr: Optional[IO[bytes]] = None
        self._stderr_saved = ""
        self._log_saved = ""
        self._stdout_rest: List[bytes] = []
        self.returncode: Optional[int] = None

    # ---- life cycle ----

    def __enter__(self) -> "Emulator":
        self.start()
        return self

    def __exit__(self, exc_type: Optional[Type[BaseException]],
                 exc: Optional[BaseException],
                 tb: Optional[TracebackType]) -> None:
        # Stop in any case; a bad exit status is reported only if the
        # block itself went well, so it does not hide the first error.
        try:
            self.stop()
        except DaemonError:
            if exc_type is None:
                raise

    def stderr_text(self) -> str:
        """What the daemon wrote on stderr so far."""
        if self._stderr is None:
            return ""
        if self._stderr.closed:
            return self._stderr_saved
        with open(self._stderr.name, "rb") as f:
            return f.read().decode("utf-8", "replace")

    def comm_log_text(self) -> str:
        """The communication log so far (comm_log=True), else "". The
        daemon flushes it after each batch of events, so what a test saw
        answered is in it."""
        if self._log is None:
            return self._log_saved
        try:
            with open(self._log, "rb") as f:
                return f.read().decode("utf-8", "replace")
        except OSError:
            return ""

    def save_capture(self, path: str) -> int:
        """Copy the capture so far (capture=True) to path; its size in
        bytes, 0 when there is none. The daemon writes it out after each
        batch of events, so what a test saw answered is in it."""
        if self.capture_path is None:
            return 0
        try:
            shutil.copyfile(self.capture_path, path)
            return os.path.getsize(path)
        except OSError:
            return 0

    def _fail(self, what: str) -> DaemonError:
        err = self.stderr_text().strip()
        return DaemonError("%s\n  command: %s\n  stderr:%s" % (
            what, " ".join(shlex.quote(a) for a in self.argv),
            ("\n    " + err.replace("\n", "\n    ")) if err else " (empty)"))

    def start(self) -> "Emulator":
        """Run the daemon and wait for its ready line; DaemonError, with
        the daemon's stderr, if it exits first or is not ready in time."""
        if self.process is not None:
            raise DaemonError("already started")
        # stderr to a file: a pipe nobody reads could fill and stall a
        # daemon that logs there (--log -).
        self._stderr = tempfile.NamedTemporaryFile(prefix="wsgemu-stderr-",
                                                   delete=False)
        try:
            self.process = subprocess.Popen(
                self.argv, stdin=subprocess.DEVNULL, stdout=subprocess.PIPE,
                stderr=self._stderr, close_fds=True)
        except OSError as e:
            self._cleanup()
            raise self._fail("cannot run wsgemu: %s" % e) from None
        try:
            line = self._read_ready_line()
            self._take_ready_line(line)
        except BaseException:
            self._kill()
            raise
        # The daemon prints nothing more on stdout, but should it, a
        # reader keeps the pipe from ever filling up.
        threading.Thread(target=self._drain_stdout, daemon=True).start()
        return self

    def _read_ready_line(self) -> str:
        assert self.process is not None and self.process.stdout is not None
        out = self.process.stdout
        buf = b""
        deadline = time.monotonic() + self.ready_timeout
        with selectors.DefaultSelector() as sel:
            sel.register(out, selectors.EVENT_READ)
            while b"\n" not in buf:
                left = deadline - time.monotonic()
                if left <= 0:
                    raise self._fail("wsgemu printed no ready line within "
                                     "%.1f s" % self.ready_timeout)
                if not sel.select(left):
                    continue
                chunk = os.read(out.fileno(), 4096)
                if not chunk:
                    # End of stdout: the daemon is gone (or closed it).
                    try:
                        rc = self.process.wait(timeout=2.0)
                    except subprocess.TimeoutExpired:
                        rc = None
                    raise self._fail(
                        "wsgemu exited with status %s before it was ready"
                        % rc if rc is not None else
                        "wsgemu closed its stdout before it was ready")
                buf += chunk
        line, _, rest = buf.partition(b"\n")
        if rest:
            self._stdout_rest.append(rest)
        return line.decode("utf-8", "replace").strip()

    def _take_ready_line(self, line: str) -> None:
        self.ready_line = line
        self.fields = parse_ready_line(line)
        if "tcp" in self.fields:
            self.tcp = [_hostport(a) for a in self.fields["tcp"].split(",")]
        if "udp" in self.fields:
            for a in self.fields["udp"].split(","):
                local, _, remote = a.partition(">")
                host, port = _hostport(local)
                self.udp.append((host, port, int(remote)))
        if "pty" in self.fields:
            self.pty = self.fields["pty"].split(",")
        if "control" in self.fields:
            self.control_addr = _hostport(self.fields["control"])

    def _drain_stdout(self) -> None:
        out = self.process.stdout if self.process else None
        try:
            while out is not None:
                chunk = os.read(out.fileno(), 4096)
                if not chunk:
                    return
                self._stdout_rest.append(chunk)
        except (OSError, ValueError):
            return

    def _kill(self) -> None:
        if self.process and self.process.poll() is None:
            self.process.kill()
            self.process.wait()
        self._cleanup()

    def _cleanup(self) -> None:
        if self.process and self.process.stdout:
            self.process.stdout.close()
        if self._stderr is not None and not self._stderr.closed:
            self._stderr_saved = self.stderr_text()
            self._stderr.close()
            try:
                os.unlink(self._stderr.name)
            except OSError:
                pass
        if self._log is not None:
            self._log_saved = self.comm_log_text()
            try:
                os.unlink(self._log)
            except OSError:
                pass
            self._log = None
        if self.capture_path is not None:
            try:
                os.unlink(self.capture_path)
            except OSError:
                pass
            self.capture_path = None

    def stop(self, timeout: float = 10.0) -> int:
        """Close the clients, send SIGTERM and wait; the exit status.
        DaemonError (with stderr) if it is not 0, if the daemon had already
        exited, or if it does not end within timeout seconds (it is then
        killed)."""
        if self.process is None:
            raise DaemonError("not started")
        if self.returncode is not None:
            return self.returncode
        self.close_clients()
        try:
            already = self.process.poll()
            if already is not None:
                self.returncode = already
                raise self._fail("wsgemu had exited with status %d before "
                                 "it was stopped" % already)
            self.process.send_signal(signal.SIGTERM)
            try:
                self.returncode = self.process.wait(timeout=timeout)
            except subprocess.TimeoutExpired:
                self.process.kill()
                self.returncode = self.process.wait()
                raise self._fail("wsgemu did not end within %.1f s of "
                                 "SIGTERM; killed" % timeout)
            if self.returncode != 0:
                raise self._fail("wsgemu exited with status %d on SIGTERM "
                                 "(expected 0)" % self.returncode)
            return self.returncode
        finally:
            self._cleanup()

    @property
    def running(self) -> bool:
        return self.process is not None and self.process.poll() is None

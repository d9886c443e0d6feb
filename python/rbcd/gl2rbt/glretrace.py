"""Mesa's replay of a capture, glretrace, as --check-depth and the read-back
textures run it: a library of ours preloaded into glretrace alone (not into
Xvfb), under xvfb-run when there is no DISPLAY, in a session of its own that
ends whole however the converter ends (start_replay, end_replay)."""
import os
import shutil
import signal
import subprocess
import time

from .errors import ToolError, printable


def preload_library(name, what, headers, package):
    """One of gl/'s libraries preloaded into glretrace, beside rbcd-gl-raster
    as bin/../lib/rbcd/ (the build tree and an installed tree alike); `what`
    needs it, and it is built with `headers` (`package` installs them)."""
    from .raster import raster_program
    lib = os.path.normpath(os.path.join(os.path.dirname(raster_program()), "..", "lib", "rbcd", name))
    if not os.path.isfile(lib):
        raise ToolError(f"{what} needs {printable(lib)}, built with the {headers} headers (scripts/setup.sh --gl "
                        f"installs {package}; then build again)")
    return lib


def glretrace_command(args, what, preload=None, env=()):
    """The command that runs glretrace with `args` (`what` needs it), with
    `preload` before any LD_PRELOAD of the caller's and `env` (name=value)
    set for glretrace."""
    exe = shutil.which("glretrace")
    if not exe:
        raise ToolError(f"{what} needs glretrace (scripts/setup.sh --gl installs apitrace)")
    cmd = [exe] + list(args)
    if preload or env:
        preload = ":".join(p for p in (preload, os.environ.get("LD_PRELOAD")) if p)
        cmd = ["env"] + ([f"LD_PRELOAD={preload}"] if preload else []) + list(env) + cmd
    if not os.environ.get("DISPLAY"):
        xvfb = shutil.which("xvfb-run")
        if not xvfb:
            raise ToolError("no DISPLAY and no xvfb-run for glretrace (scripts/setup.sh --gl installs xvfb)")
        cmd = [xvfb, "-a", "-s", "-screen 0 1280x1024x24"] + cmd
    return cmd


# The seconds the replay's processes get to end on SIGTERM (Xvfb then
# removes its lock file and socket) before SIGKILL.
END_SECONDS = 2
# The shell a replay runs under (start_replay). Its standard input is the
# read end of a pipe whose one write end the converter holds: its watcher
# (a shell named WATCHER) reads the end of the file when the converter
# ends, however it ends (the watchdog's os._exit, SIGKILL), and sends
# SIGTERM to the session's process group: the shell, xvfb-run, the Xvfb it
# starts in the background (a shell without job control keeps it in the
# shell's group), glretrace; then, ignoring SIGTERM itself, SIGKILL to what
# is left END_SECONDS later (glretrace's own SIGTERM handler can deadlock
# on malloc's lock, and it had lived on). The command runs in the
# foreground (an asynchronous list would ignore SIGINT and SIGQUIT), and its
# status is the shell's; ended, the shell ends the watcher with SIGKILL.
WATCHER = "rbcd-replay-watcher"
SESSION = f"""exec 3<&0 </dev/null
sh -c 'trap "" TERM; read -r _; kill -TERM 0; sleep {END_SECONDS}; kill -KILL 0' {WATCHER} <&3 &
exec 3<&-
"$@"
status=$?
kill -KILL $! 2>/dev/null
exit $status
"""


def start_replay(cmd, **popen):
    """Starts `cmd` (glretrace_command's) under SESSION, in a session of its
    own: the terminal's Ctrl-C reaches the converter alone, which ends the
    replay with end_replay on every path; `popen`: Popen's other
    arguments."""
    r, w = os.pipe()   # neither inherited by other children; r becomes the shell's standard input
    try:
        proc = subprocess.Popen(["/bin/sh", "-c", SESSION, "rbcd-replay"] + list(cmd), stdin=r,
                                start_new_session=True, **popen)
    except BaseException:
        os.close(w)   # a shell started all the same ends its session at once
        raise
    finally:
        os.close(r)
    proc.rbcd_lifeline = w
    return proc


def session_left(sid, watcher=False):
    """The processes of session `sid` still running (a zombie is not), as
    (pid, state) with state /proc's letter (T or t: stopped); the watcher
    (SESSION's, which outlives SIGTERM on purpose) only when `watcher`."""
    left = []
    for entry in os.listdir("/proc"):
        if not entry.isdigit():
            continue
        try:
            with open(f"/proc/{entry}/stat", "rb") as f:
                fields = f.read().rsplit(b")", 1)[1].split()
            if len(fields) > 3 and fields[3] == str(sid).encode() and fields[0] != b"Z":
                if not watcher:
                    with open(f"/proc/{entry}/cmdline", "rb") as f:
                        if WATCHER.encode() in f.read().split(b"\0"):
                            continue
                left.append((int(entry), fields[0].decode()))
        except (OSError, IndexError):
            continue
    return left


def end_replay(proc):
    """Ends a replay start_replay started and every process of its session
    (xvfb-run's Xvfb too): SIGTERM (and SIGCONT, which a stopped one needs
    to take it), SIGKILL to those left after END_SECONDS; returns once none
    runs, the shell reaped. A signal's KeyboardInterrupt while it works is
    raised once the session has ended (the converter ignores the signals
    from the first on: cli.on_signal)."""
    try:
        _end_session(proc)
    except KeyboardInterrupt:
        _end_session(proc)
        raise


def _end_session(proc):
    # The group is signalled only while a process of the session runs: its
    # id is then no other group's (a reaped shell's pid is free for reuse
    # only once no process of its session is left).
    for sig in (signal.SIGTERM, signal.SIGKILL):
        if not session_left(proc.pid):
            break
        try:
            os.killpg(proc.pid, sig)
            os.killpg(proc.pid, signal.SIGCONT)
        except ProcessLookupError:
            break
        deadline = time.monotonic() + END_SECONDS
        while session_left(proc.pid) and time.monotonic() < deadline:
            time.sleep(0.01)
    for pid, _ in session_left(proc.pid, watcher=True):
        try:
            os.kill(pid, signal.SIGKILL)   # the watcher, the session's last
        except ProcessLookupError:
            pass
    # (SIGKILL is sent, not yet taken: the watcher runs until it is)
    deadline = time.monotonic() + END_SECONDS
    while session_left(proc.pid, watcher=True) and time.monotonic() < deadline:
        time.sleep(0.01)
    proc.wait()
    w = getattr(proc, "rbcd_lifeline", None)
    if w is not None:
        os.close(w)
        proc.rbcd_lifeline = None

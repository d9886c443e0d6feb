"""Captures read through apitrace's own reader (`apitrace pickle`), call by call."""
import pickle
import shutil
import signal
import subprocess
import sys
import tempfile

from .errors import ConvertError, ToolError, printable


def where(last):
    return f"after call {last}" if last is not None else "before its first call"


def apitrace_tool():
    exe = shutil.which("apitrace")
    if not exe:
        raise ConvertError("apitrace is not installed (scripts/setup.sh --gl installs it)")
    return exe


# The values one call may carry: the elements of its lists, tuples and dicts,
# all levels counted, every reference counted (a list naming one list twice
# counts it twice). The game suite's calls carry at most 31; a reduced
# capture of 11 KB can carry a list of 30 million references, which the
# handlers would walk for seconds (and one of shared references, 10^9).
MAX_RECORD_VALUES = 1 << 20


_CONTAINERS = (list, tuple, dict)   # what a pickle read by CallReader can nest


def call_values_within(call, limit=MAX_RECORD_VALUES):
    """Whether the call (no, name, args, ret, flags) carries at most `limit`
    values in its arguments and return value (MAX_RECORD_VALUES). The walk
    stops as soon as the count passes the limit, so it costs at most `limit`
    steps whatever the call holds (about a microsecond for a call of scalar
    arguments: a tenth of reading it)."""
    args = call[2]
    n = len(args)
    if n > limit:
        return False
    stack = []
    for a in args:   # (name, value) pairs; anything else walked whole
        if type(a) is tuple:
            for v in a:
                if type(v) in _CONTAINERS:
                    stack.append(v)
        elif type(a) in _CONTAINERS:
            stack.append(a)
    if type(call[3]) in _CONTAINERS:
        stack.append(call[3])
    while stack:
        x = stack.pop()
        n += len(x)
        if n > limit:
            return False
        if type(x) is dict:
            n += len(x)
            x = (*x.keys(), *x.values())
        for y in x:
            if type(y) in _CONTAINERS:
                stack.append(y)
    return True


def too_many_values(no):
    return ConvertError(f"call {no}: more than {MAX_RECORD_VALUES} values in one call (the limit; "
                        "docs/gl-capture.md)")


class PointerType(int):
    """apitrace's pickled pointers (unpickle.Pointer): an address."""


def _dealloc_report_dropped(kind, value, tb):
    """sys.excepthook while a pickle is read: CPython's unpickler, failing
    on a corrupt length, frees a bytearray a view of which is still alive
    and reports that from the deallocator through sys.excepthook
    ("SystemError: deallocated bytearray object has exported buffers");
    the reader's own error says what failed, so that report is dropped.
    Anything else goes to Python's hook."""
    if not (kind is SystemError and "exported buffers" in str(value)):
        sys.__excepthook__(kind, value, tb)


class CallReader(pickle.Unpickler):
    def find_class(self, module, name):
        if name == "Pointer":
            return PointerType
        raise pickle.UnpicklingError(f"unexpected object {module}.{name} in the pickle stream")

    def load(self):
        sys.excepthook = _dealloc_report_dropped
        try:
            return super().load()
        finally:
            sys.excepthook = sys.__excepthook__


def read_apitrace_calls(trace, calls=None):
    """Yields (no, name, args, ret, flags) from `apitrace pickle` (only the
    calls `calls` names, in apitrace's --calls syntax, when given);
    ConvertError when apitrace refuses the file or it ends early."""
    cmd = [apitrace_tool(), "pickle", "--symbolic"]
    if calls:
        cmd.append(f"--calls={calls}")
    cmd.append(trace)
    err = tempfile.TemporaryFile()
    p = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=err, stdin=subprocess.DEVNULL)
    last = None
    stopped = ended = False
    undecoded = None
    try:
        reader = CallReader(p.stdout)
        while True:
            try:
                c = reader.load()
            except EOFError:
                ended = True
                break
            except (pickle.UnpicklingError, ValueError, TypeError, AttributeError, IndexError, MemoryError) as e:
                undecoded = f"the capture does not decode ({printable(e, 80)})"
                break
            if not (isinstance(c, tuple) and len(c) == 5 and isinstance(c[0], int) and isinstance(c[1], str)
                    and isinstance(c[2], list) and 0 <= c[0] <= (1 << 63) - 1):
                undecoded = "the capture does not decode (unexpected record)"
                break
            if not call_values_within(c):
                raise too_many_values(c[0])
            last = c[0]
            if (yield c) is not None:
                # capture.check_rest: reading stops at the last frame asked
                # for, and what apitrace says of the rest is not read.
                stopped = True
                break
    finally:
        # apitrace has ended its output, or will once it is read to the
        # end: a moment to exit before it is stopped (then by us).
        if (ended or undecoded is not None) and p.poll() is None:
            try:
                p.wait(timeout=5)
            except subprocess.TimeoutExpired:
                pass
        ours = p.poll() is None
        if ours:
            p.kill()
        p.stdout.close()
        rc = p.wait()
    if stopped:
        return
    if rc < 0 and not ours:
        if -rc in (signal.SIGINT, signal.SIGTERM, signal.SIGHUP):
            raise KeyboardInterrupt   # the run's group was signalled: interrupted (rbcd.gl2rbt.cli)
        if -rc != signal.SIGKILL:
            # apitrace's reader crashed (SIGSEGV on bytes overwritten): the
            # capture does not decode.
            raise ConvertError(f"{where(last)}: the capture does not decode (apitrace crashed on it: signal {-rc})")
        # Killed from outside (SIGKILL, the kernel out of memory): what it
        # gave is not the whole capture, and the capture is not to blame.
        raise ToolError(f"{printable(trace)}: {where(last)}: apitrace pickle, reading the capture, was ended by "
                        f"signal {-rc}; no output written")
    if undecoded is not None:
        raise ConvertError(f"{where(last)}: {undecoded}")
    err.seek(0)
    msg = err.read(4096).decode("utf-8", "replace")
    bad = [l for l in msg.splitlines() if "error" in l.lower() or "warning: unexpected end" in l.lower()
           or "truncated" in l.lower() or "unsupported" in l.lower() or "failed" in l.lower()]
    if rc != 0 and not ours:
        raise ConvertError(f"{where(last)}: apitrace cannot read the capture: "
                           f"{printable((bad or msg.splitlines() or ['exit %d' % rc])[0])}")
    if bad:
        raise ConvertError(f"{where(last)}: {printable(bad[0])}")

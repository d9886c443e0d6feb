"""Captures read through apitrace's own reader (`apitrace pickle`), call by call."""
import pickle
import shutil
import signal
import subprocess
import tempfile

from .errors import ConvertError, printable


def where(last):
    return f"after call {last}" if last is not None else "before its first call"


def apitrace_tool():
    exe = shutil.which("apitrace")
    if not exe:
        raise ConvertError("apitrace is not installed (scripts/setup.sh --gl installs it)")
    return exe


class PointerType(int):
    """apitrace's pickled pointers (unpickle.Pointer): an address."""


class CallReader(pickle.Unpickler):
    def find_class(self, module, name):
        if name == "Pointer":
            return PointerType
        raise pickle.UnpicklingError(f"unexpected object {module}.{name} in the pickle stream")


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
    try:
        reader = CallReader(p.stdout)
        while True:
            try:
                c = reader.load()
            except EOFError:
                break
            except (pickle.UnpicklingError, ValueError, TypeError, AttributeError, IndexError, MemoryError) as e:
                raise ConvertError(f"{where(last)}: the capture does not decode ({printable(e, 80)})")
            if not (isinstance(c, tuple) and len(c) == 5 and isinstance(c[0], int) and isinstance(c[1], str)
                    and isinstance(c[2], list) and 0 <= c[0] <= (1 << 63) - 1):
                raise ConvertError(f"{where(last)}: the capture does not decode (unexpected record)")
            last = c[0]
            yield c
    finally:
        if p.poll() is None:
            p.kill()
        p.stdout.close()
        rc = p.wait()
    err.seek(0)
    msg = err.read(4096).decode("utf-8", "replace")
    bad = [l for l in msg.splitlines() if "error" in l.lower() or "warning: unexpected end" in l.lower()
           or "truncated" in l.lower() or "unsupported" in l.lower() or "failed" in l.lower()]
    if rc != 0 and rc != -signal.SIGKILL:
        raise ConvertError(f"{where(last)}: apitrace cannot read the capture: "
                           f"{printable((bad or msg.splitlines() or ['exit %d' % rc])[0])}")
    if bad:
        raise ConvertError(f"{where(last)}: {printable(bad[0])}")

"""The converter's errors and how it names what it read."""
import threading

from ..cli import UsageError, describe, escape, exception_text

# Held by whichever thread says the run's last line (the main thread, or
# the watchdog that ends the run while Mesa works): one line, never two.
LAST_WORD = threading.Lock()


class ConvertError(UsageError):
    """Bad input (a capture, a reduced capture, a selection file, the command
    line): one line, exit 2."""


class ToolError(Exception):
    """A tool failed: one line, exit 1."""


class RasterStopped(Exception):
    """rbcd-gl-raster exited early: its own message says why."""


def printable(s, limit=200):
    """One line (rbcd.cli.escape: non-printable bytes as \\xNN), cut at
    `limit`; in time and memory bounded by `limit`, whatever `s` is: text is
    cut before it is escaped, an exception's arguments and any other value
    are described (rbcd.cli.describe), never written out whole."""
    if isinstance(s, BaseException):
        s = exception_text(s, limit)
    elif not isinstance(s, (str, bytes, bytearray)):
        return describe(s, limit)
    s = escape(bytes(s[:limit + 1]) if isinstance(s, bytearray) else s[:limit + 1])
    return s if len(s) <= limit else s[:limit] + "..."


def fail_call(no, what):
    raise ConvertError(f"call {no}: {what}")


def checked(no, check, *args):
    """check(*args) of rbcd.cli's input rule (integer, real), its failure as
    the capture's error at call `no`."""
    try:
        return check(*args)
    except UsageError as e:
        raise ConvertError(f"call {no}: {e}") from None

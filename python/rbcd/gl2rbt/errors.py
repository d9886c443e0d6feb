"""The converter's errors and how it names what it read."""
from ..cli import UsageError, escape


class ConvertError(UsageError):
    """Bad input (a capture, a reduced capture, a selection file, the command
    line): one line, exit 2."""


class ToolError(Exception):
    """A tool failed: one line, exit 1."""


class RasterStopped(Exception):
    """rbcd-gl-raster exited early: its own message says why."""


def printable(s, limit=200):
    """One line (rbcd_cli.escape: non-printable bytes as \\xNN), cut at `limit`."""
    s = escape(s)
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

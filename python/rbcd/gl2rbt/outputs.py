"""Streamed outputs by the project's rules (docs/limits.md)."""
import os

from ..cli import output_target, temporary_file, unregister_temporary
from .errors import ConvertError, ToolError, printable

class SafeText:
    """A streamed output by the project's rules (rbcd.cli.output_target;
    rbcd.cli.write_output for whole outputs): a path that is absent or a
    regular file, also through a symlink to one, is written to an
    unpredictable temporary renamed over it on success and removed
    otherwise; anything else (a FIFO, a device) is written in place and
    never unlinked."""

    def __init__(self, path, binary=False):
        self.path, self.tmp = path, None
        how, self.target = output_target(path)
        try:
            if os.path.isdir(path):
                raise IsADirectoryError(21, "is a directory")
            if how == "in place":
                fd = os.open(path, os.O_WRONLY | os.O_NOCTTY | os.O_CLOEXEC)
            else:
                d = os.path.dirname(os.path.abspath(self.target))
                fd, self.tmp = temporary_file(d, "." + os.path.basename(self.target) + ".")
        except OSError as e:
            raise ConvertError(f"{printable(path)}: cannot create: {printable(e.strerror)}")
        self.f = os.fdopen(fd, "wb" if binary else "w", buffering=1 << 20)

    def write(self, s):
        try:
            self.f.write(s)
        except OSError as e:
            raise ToolError(f"{printable(self.path)}: write failed: {printable(e.strerror)}")

    def commit(self):
        try:
            self.f.close()
        except OSError as e:
            raise ToolError(f"{printable(self.path)}: write failed: {printable(e.strerror)}")
        if self.tmp:
            os.chmod(self.tmp, 0o666 & ~current_umask())
            os.replace(self.tmp, self.target)
            unregister_temporary(self.tmp)
            self.tmp = None

    def abandon(self):
        try:
            self.f.close()
        except OSError:
            pass
        if self.tmp:
            try:
                os.unlink(self.tmp)
            except OSError:
                pass
            unregister_temporary(self.tmp)
            self.tmp = None


def current_umask():
    m = os.umask(0)
    os.umask(m)
    return m

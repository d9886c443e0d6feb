"""The capture, whichever form it comes in: apitrace's, or a reduced capture."""
import os
import stat

from .apitrace import read_apitrace_calls
from .errors import ConvertError, printable
from .reduced import CHECK_REST, header_version, is_reduced_capture, read_reduced_calls, reduced_header


def read_calls(trace, calls=None):
    """Yields (no, name, args, ret, flags) from `apitrace pickle`, or from a
    reduced capture; ConvertError when apitrace refuses the file or it ends
    early."""
    if is_reduced_capture(trace):
        if calls:
            raise ConvertError("a reduced capture cannot be replayed: give the capture itself")
        yield from read_reduced_calls(trace)
    else:
        yield from read_apitrace_calls(trace, calls)


def close_calls(calls, conv):
    """The end of a loop over read_calls' generator, however it ends: the
    generator closed here (apitrace's process ended), not when Python
    collects it, where a signal's KeyboardInterrupt raised in its clean-up
    would be printed as ignored and lost; then the converter's replay
    closed, whatever the first raised."""
    try:
        calls.close()
    finally:
        conv.close_replay()


def shows_every_gen(trace):
    """Whether the capture shows every glGenFramebuffers and
    glGenRenderbuffers call (a core profile then binds only the names they
    returned): an apitrace capture records every call, and a reduced
    capture keeps them from version 2 on. A reduced capture of version 1
    dropped them: the names it binds are taken as it binds them."""
    if not is_reduced_capture(trace):
        return True
    try:
        return (header_version(reduced_header(trace)) or 0) >= 2
    except ConvertError:
        return False   # read_reduced_calls names the file's error


def shows_every_image(trace):
    """Whether the capture shows every call that gives a texture images:
    an apitrace capture does, and a reduced capture from version 5 on;
    earlier ones kept those of 2D textures and cube maps alone."""
    if not is_reduced_capture(trace):
        return True
    try:
        return (header_version(reduced_header(trace)) or 0) >= 5
    except ConvertError:
        return False


def check_rest(calls):
    """When the converter stops reading at the last frame asked for, before
    the capture's end: a reduced capture's rest is checked (its xz stream to
    its end, and its end record: reduced.check_rest); an apitrace capture's
    is not read (docs/gl-capture.md, "Bad input")."""
    try:
        calls.send(CHECK_REST)
    except StopIteration:
        pass


def check_input_file(path):
    """The capture: a regular file we can read (messages follow its name)."""
    if path == "-":
        raise ConvertError("standard input cannot be a capture (apitrace reads files)")
    try:
        st = os.stat(path)
    except OSError as e:
        raise ConvertError(f"cannot open: {printable(e.strerror)}")
    if not stat.S_ISREG(st.st_mode):
        raise ConvertError("not a regular file")
    if not os.access(path, os.R_OK):
        raise ConvertError("cannot open: permission denied")

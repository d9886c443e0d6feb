"""What the project's Python tools share with rbcd-sim's
rules for inputs, outputs and messages (docs/limits.md), in one place:

    from rbcd.cli import UsageError, read_input, write_output, main_wrapper

- Messages are one line: bytes that are not printable are written as \\xNN (as
  rbcd-sim's escape_for_message does; also Unicode's format, bidirectional
  and other invisible characters, U+202E say) and a token longer than 1024
  characters is cut. Errors are exit 2 (UsageError) or 1 (anything else, "internal
  error"), never a traceback.
- Inputs are regular files, opened without waiting on a FIFO, read up to a
  stated limit, with the same wording as rbcd-sim: "PATH: cannot read WHAT:
  REASON".
- Outputs are written as rbcd-sim writes them: a path that is absent or a
  regular file through an unpredictable temporary beside it (O_EXCL, never a
  planted symlink followed), renamed over it when complete, also through a
  symlink to one (the temporary beside the link's target, which a failed run
  leaves as it was); anything else (a device, a FIFO) written in place and
  never unlinked. check_outputs refuses, before anything is opened, an output
  that names an input or another output, or a FIFO or socket other than
  standard output (opening one would wait for a reader), and standard
  output opened onto an input (the report would go into it). A temporary
  is removed on failure and on SIGINT/SIGTERM/SIGHUP (main_wrapper turns them
  into KeyboardInterrupt, so that cleanup code runs).
"""
import argparse
import errno
import gzip
import io
import math
import os
import re
import secrets
import shutil
import signal
import stat
import sys
import tempfile
import tomllib
import unicodedata

from .startup import HANDLED, ignore_signals, kept, release_signals

MAX_TOKEN = 1024


class UsageError(Exception):
    """Bad input or command line: one line, exit 2."""


class WriteError(Exception):
    """An output that could be created but not written (a full device, a
    rename refused): "PATH: write failed: REASON", one line, exit 1."""


# ---- the input rule: every value read from an input file, checked before use
# for its type, finiteness and range (the C structs it is packed into, or
# what the format allows), and named in the message when it fails.

I32 = (-(1 << 31), (1 << 31) - 1)
U32 = (0, (1 << 32) - 1)
U63 = (0, (1 << 63) - 1)
I64 = (-(1 << 63), (1 << 63) - 1)


def integer(v, what, lo, hi):
    """v, an integer in [lo, hi] (a bool is not one); UsageError naming `what`."""
    if isinstance(v, bool) or not isinstance(v, int):
        raise UsageError(f"{what}: {describe(v)} is not an integer")
    if not lo <= v <= hi:
        raise UsageError(f"{what}: {describe(v)} is outside [{lo}, {hi}]")
    return v


def real(v, what, lo=None, hi=None):
    """v, a finite number in [lo, hi] (either bound may be None), as a float."""
    if isinstance(v, bool) or not isinstance(v, (int, float)):
        raise UsageError(f"{what}: {describe(v)} is not a number")
    if isinstance(v, float) and v != v or v in (float("inf"), float("-inf")):
        raise UsageError(f"{what}: {v} is not finite")
    if (lo is not None and v < lo) or (hi is not None and v > hi):
        raise UsageError(f"{what}: {describe(v)} is outside [{lo}, {hi}]")
    try:
        return float(v)
    except OverflowError:
        raise UsageError(f"{what}: {describe(v)} is too large")


# A value described in a message: containers to this depth and this many
# items, integers written out up to this many bits.
DESCRIBE_DEPTH, DESCRIBE_ITEMS, DESCRIBE_BITS = 2, 4, 128


def describe(v, limit=60):
    """A value read from an input, for a message: one escaped line of at
    most `limit` characters, built in time and memory bounded whatever the
    value holds. Only a bounded part of it is ever looked at: a string's
    first `limit` characters, a container's first DESCRIBE_ITEMS items to
    DESCRIBE_DEPTH levels (a pickle of shared references can make a list of
    10^9 elements out of a kilobyte; its repr would take gigabytes), bytes
    and long integers by their size."""
    text = escape(_describe(v, DESCRIBE_DEPTH, limit))
    return text if len(text) <= limit else text[:limit - 3] + "..."


def _describe(v, depth, limit):
    if v is None or isinstance(v, (bool, float)):
        return repr(v)
    if isinstance(v, int):
        bits = v.bit_length()
        return repr(int(v)) if bits <= DESCRIBE_BITS else f"an integer of {bits} bits"
    if isinstance(v, str):
        return repr(v[:limit]) + ("..." if len(v) > limit else "")
    if isinstance(v, (bytes, bytearray, memoryview)):
        return f"{len(v)} bytes"
    if isinstance(v, (list, tuple)):
        kind = "a list" if isinstance(v, list) else "a tuple"
        if depth <= 0 or len(v) > DESCRIBE_ITEMS:
            return f"{kind} of {len(v)} elements"
        inner = ", ".join(_describe(x, depth - 1, limit) for x in v)
        return f"[{inner}]" if isinstance(v, list) else f"({inner}{',' if len(v) == 1 else ''})"
    if isinstance(v, dict):
        return f"a dict of {len(v)} entries"
    return f"a {type(v).__name__}"


def exception_text(e, limit=200):
    """An exception's message, bounded as describe() is: str(e) when its
    arguments are text and small numbers (its own wording), else its
    arguments described (a KeyError's key, say, can be any value read);
    its type's name when it has no words (a MemoryError, say)."""
    if not e.args or e.args == ("",):
        return type(e).__name__
    if all(a is None or isinstance(a, (str, bool, float)) or isinstance(a, int) and a.bit_length() <= DESCRIBE_BITS
           or isinstance(a, bytes) and len(a) <= limit for a in e.args) \
            and (len(e.args) == 1 or sum(len(a) for a in e.args if isinstance(a, str)) <= limit * 4):
        return str(e)
    return ", ".join(describe(a, limit) for a in e.args[:DESCRIBE_ITEMS])


def _escape_char(ch):
    """ch itself when it prints as itself: not a character of category Cc
    (controls: LF, CR, ESC, DEL, C1), Cf (format: U+202E RIGHT-TO-LEFT
    OVERRIDE, which makes a terminal show the rest of a line reversed, the
    other bidirectional controls, U+200B), Cs (surrogates), Co (private
    use), Cn (unassigned), Zl or Zp (U+2028, U+2029); else its UTF-8 bytes as
    \\xNN. str.isprintable() is False exactly for those categories and Zs
    (spaces, kept: they print as a space)."""
    if ch.isprintable() or unicodedata.category(ch) == "Zs":
        return ch
    cp = ord(ch)
    if 0xdc80 <= cp <= 0xdcff:   # a byte that was not UTF-8 (surrogateescape)
        return f"\\x{cp - 0xdc00:02x}"
    return "".join(f"\\x{b:02x}" for b in ch.encode("utf-8", "surrogatepass"))


def escape(text):
    """One printable line: control characters (LF, CR, ESC, ...), DEL, C1 controls,
    format and bidirectional controls (U+202E), line and paragraph separators,
    private-use and unassigned characters and invalid UTF-8 as \\xNN; tokens
    longer than MAX_TOKEN characters cut."""
    if isinstance(text, bytes):
        text = text.decode("utf-8", "surrogateescape")
    out = str(text)
    if not out.isprintable():   # (the common case, a printable line, checked in C)
        out = "".join(c if c.isprintable() else _escape_char(c) for c in out)
    return re.sub(r"\S{%d,}" % (MAX_TOKEN + 1),
                  lambda m: m.group(0)[:MAX_TOKEN] + f"...({len(m.group(0))} characters)", out)


def say(prog, text):
    """One line on stderr, escaped."""
    sys.stderr.write(f"{prog}: {escape(text)}\n")
    sys.stderr.flush()


# ---- the command line, as every tool takes it: an option's name whole (no
# abbreviation: --geom is not --geometry), an option that takes a value at
# most once (a second had replaced the first), numbers in ASCII digits
# (int() and float() also take other scripts' digits, '1_0' and ' 1 '), an
# error one line and exit 2.

class ArgumentParser(argparse.ArgumentParser):
    """argparse's parser without abbreviations; its error is the tool's
    UsageError "MESSAGE (see --help)": one line naming the tool, exit 2
    (main_wrapper; rbcd.gl2rbt.cli.main). Sub-commands' parsers
    (add_subparsers) are of the same class."""

    def __init__(self, *args, **kw):
        kw["allow_abbrev"] = False
        super().__init__(*args, **kw)

    def add_subparsers(self, **kw):
        kw.setdefault("parser_class", type(self))
        return super().add_subparsers(**kw)

    def error(self, message):
        raise UsageError(f"{message} (see --help)")

    def print_help(self, file=None):
        """--help: the whole text on standard output or none of it (a write
        that fails is WriteError, one line, exit 1). The text
        is made first; it is written and flushed with SIGINT, SIGTERM and
        SIGHUP held, and exit (argparse's next call) ignores them, which
        drops one held meanwhile: a signal cannot cut the help short, nor
        come after a whole help and end the run as "interrupted", exit 130
        (a signal that came before the hold is taken at once, before a
        byte is written)."""
        if file is not None:
            return super().print_help(file)
        text = self.format_help()
        signal.pthread_sigmask(signal.SIG_BLOCK, HANDLED)
        try:
            sys.stdout.write(text)
            sys.stdout.flush()
        except OSError as e:   # (a full device, a closed pipe)
            raise WriteError(f"standard output: write failed: {e.strerror}") from None

    def exit(self, status=0, message=None):
        """The end of --help: the work is done, a signal from here changes
        nothing (main_wrapper's clean-up ignores them too)."""
        ignore_signals()
        signal.pthread_sigmask(signal.SIG_UNBLOCK, HANDLED)
        super().exit(status, message)


class Once(argparse.Action):
    """An option given once: a second one is the command line's error."""

    def __call__(self, parser, namespace, values, option_string=None):
        given = namespace.__dict__.setdefault("_given", set())
        if self.dest in given:
            parser.error(f"{option_string} is given twice")
        given.add(self.dest)
        setattr(namespace, self.dest, values)


class OnceFlag(Once):
    """A flag (store_true) given once: a second one is the command line's error."""

    def __init__(self, option_strings, dest, default=False, **kw):
        super().__init__(option_strings, dest, nargs=0, default=default, **kw)

    def __call__(self, parser, namespace, values, option_string=None):
        super().__call__(parser, namespace, True, option_string)


def ascii_int(text):
    """An integer in ASCII digits."""
    if not re.fullmatch(r"[+-]?[0-9]{1,18}", text):
        raise argparse.ArgumentTypeError(f"invalid integer: {text!r}")
    return int(text)


def finite_float(text):
    """A finite decimal number in ASCII (float() also takes 'nan', 'inf' and 1e999)."""
    if not re.fullmatch(r"[+-]?([0-9]{1,18}(\.[0-9]{0,18})?|\.[0-9]{1,18})([eE][+-]?[0-9]{1,3})?", text) \
            or not math.isfinite(float(text)):
        raise argparse.ArgumentTypeError(f"invalid number: {text!r}")
    return float(text)


def _kind(mode):
    return ("a directory" if stat.S_ISDIR(mode) else "a character device" if stat.S_ISCHR(mode)
            else "a block device" if stat.S_ISBLK(mode) else "a FIFO" if stat.S_ISFIFO(mode)
            else "a socket" if stat.S_ISSOCK(mode) else "not a file")


def cannot_read(path, what, reason):
    return UsageError(f"{path}: cannot read {what}: {reason}")


def read_input(path, what, max_bytes, limit_key=""):
    """The bytes of a regular file of at most max_bytes; UsageError otherwise."""
    try:
        fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK | os.O_CLOEXEC)
    except OSError as e:
        raise cannot_read(path, what, e.strerror)
    try:
        st = os.fstat(fd)
        if not stat.S_ISREG(st.st_mode):
            raise cannot_read(path, what, f"is {_kind(st.st_mode)}, not a regular file")
        os.set_blocking(fd, True)
        chunks, n = [], 0
        while True:
            b = os.read(fd, 1 << 16)
            if not b:
                break
            n += len(b)
            if n > max_bytes:
                raise UsageError(f"{path}: {what} larger than {max_bytes} bytes (the limit"
                                 + (f", raised by {limit_key}" if limit_key else ", fixed") + "; docs/limits.md)")
            chunks.append(b)
        return b"".join(chunks)
    except OSError as e:
        raise cannot_read(path, what, e.strerror)
    finally:
        os.close(fd)


GZIP_MAGIC = b"\x1f\x8b"
ZSTD_MAGIC = b"\x28\xb5\x2f\xfd"


def trace_compression(path):
    """"gzip", "zstd" or None, by the file's first bytes (docs/formats.md: a
    trace is recognised by its magic, whatever its name)."""
    with open(path, "rb") as f:
        magic = f.read(4)
    if magic[:2] == GZIP_MAGIC:
        return "gzip"
    if magic == ZSTD_MAGIC:
        return "zstd"
    return None


def open_trace(path):
    """A trace's bytes as a binary file, decompressed when it is gzip or zstd.
    Its read errors: OSError, EOFError and trace_errors()."""
    kind = trace_compression(path)
    if kind == "gzip":
        return gzip.open(path, "rb")
    if kind == "zstd":
        try:
            import zstandard
        except ImportError:
            raise UsageError(f"{path}: a zstd-compressed trace: reading it here needs python3-zstandard "
                             "(scripts/setup.sh --gl installs it)") from None
        raw = open(path, "rb")
        # A window of at most 2^27 bytes, as rbcd-sim allows.
        reader = zstandard.ZstdDecompressor(max_window_size=1 << 27).stream_reader(
            raw, read_across_frames=True, closefd=True)
        return io.BufferedReader(reader, 1 << 20)
    return open(path, "rb")


def trace_errors():
    """What reading a compressed trace raises on a corrupt file, beside OSError
    and EOFError. A function, called in except clauses (evaluated only when an
    exception gets there), so that no tool imports zstandard (10 ms) to start."""
    try:
        import zstandard
    except ImportError:
        return (gzip.BadGzipFile,)
    return (gzip.BadGzipFile, zstandard.ZstdError)


def read_input_text(path, what, max_bytes, limit_key=""):
    data = read_input(path, what, max_bytes, limit_key)
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as e:
        raise UsageError(f"{path}: {what}: not UTF-8 text (byte {e.start})")


# ---- TOML: what Python's tomllib does not bound. Its work and memory for a
# dotted key grow with the square of its parts (a key of 40,000 parts, an
# 80 KB file, took 6.3 GB), so a key of more than TOML_KEY_PARTS parts, in a
# key/value line, a [table] or [[array]] header or an inline table, is
# refused before tomllib sees the text. (Nesting too deep is tomllib's
# RecursionError, which each reader turns into its own one line.)
TOML_KEY_PARTS = 64
# The scan keeps its memory small: Python's re stacks a frame (about 150
# bytes) for each repetition of a group while it matches, so a string is
# matched by repeats of single characters only (a 4 MiB string costs no more
# than a short one) and a run of dotted parts by at most TOML_KEY_PARTS
# repetitions at a time (then _TOML_MORE's, 4096 at a time). For that, every
# pair of backslashes is first replaced by two NULs (the same length, so
# positions and lines stay): a run of backslashes starts where a string's
# escape may start (it follows a character that is no backslash), so the
# pairs are the escapes "\\" a string would read, and NUL is, like
# them, nothing but a string's character; what is left of a backslash is
# alone and escapes the one character after it. A basic string then ends at
# the first quote (or line end, or a lone backslash before one, or the
# text's end) that no backslash precedes.
_TOML_BASIC = r'"[^"\\\n]*[^\n]*?(?=(?<!\\)(?:"|\\?(?:\n|\Z)))"?'
_TOML_PART = r"[A-Za-z0-9_-]+|" + _TOML_BASIC + r"|'[^'\n]*'?"
_TOML_DOT_PART = r"[ \t]*\.[ \t]*(?:%s)" % _TOML_PART
# One pass over the text, linear: multi-line strings (to their end, or the
# text's when unterminated) and comments are skipped; every run of key parts
# joined by dots (a single-line string is one part) is a match of its own,
# its parts counted only when it holds more dots than the limit allows.
# Outside strings and comments a TOML document's only such runs are keys,
# floats and times' fractional seconds (2 parts).
_TOML_SCAN_REST = (r"'''[\s\S]*?(?:'''|\Z)|#[^\n]*|"
                   + r"(?P<key>(?:%s)(?:%s){0,%d})" % (_TOML_PART, _TOML_DOT_PART, TOML_KEY_PARTS))
_TOML_SCAN = re.compile(r'"""[\s\S]*?(?<!\\)(?:"""|\Z)|' + _TOML_SCAN_REST)
# A multi-line basic string finds no end only in a text that ends with a
# lone backslash (an escape of nothing), and only when no string end follows
# it; every one opened after it then fails alike, each after reading to the
# text's end again (a time that grows with the square of the text), so the
# rest of the text is scanned without trying them (its quotes are parts of
# keys, as they are when the string fails).
_TOML_SCAN_OPEN = re.compile(_TOML_SCAN_REST)
_TOML_MORE = re.compile(r"(?:%s){1,4096}" % _TOML_DOT_PART)
_TOML_PARTS = re.compile(_TOML_PART)


def _toml_keys(text):
    """(start, end, parts) of every run of dotted key parts in a TOML text,
    in order; parts is counted only for a run of at least TOML_KEY_PARTS
    dots, else None."""
    scan = text.replace("\\\\", "\0\0")
    scanner = _TOML_SCAN
    pos = 0
    while m := scanner.search(scan, pos):
        pos = m.end()
        if m.start("key") < 0:
            continue
        start, parts = m.start(), None
        if scan.startswith('"""', start):    # a multi-line basic string with no end
            scanner = _TOML_SCAN_OPEN
        if scan.count(".", start, pos) >= TOML_KEY_PARTS:
            # Past TOML_KEY_PARTS + 1 parts the match may have stopped at
            # its bound: the run goes on while a dotted part follows.
            while more := _TOML_MORE.match(scan, pos):
                pos = more.end()
            parts = sum(1 for _ in _TOML_PARTS.finditer(scan, start, pos))
        yield start, pos, parts


def check_toml_keys(path, text):
    """UsageError "PATH:LINE: a key of N dotted parts, more than
    TOML_KEY_PARTS" for the first such key of a TOML text, before tomllib
    parses it (parse_toml). Linear in the text, in time and memory; a text
    that is not TOML may be refused here rather than by tomllib, never a TOML
    document whose keys are all within the limit."""
    for start, _, parts in _toml_keys(text):
        if parts is not None and parts > TOML_KEY_PARTS:
            line = text.count("\n", 0, start) + 1
            raise UsageError(f"{path}:{line}: a key of {parts} dotted parts, more than {TOML_KEY_PARTS}")
    return text


def parse_toml(path, text):
    """A TOML text as tomllib reads it, its keys bounded first
    (check_toml_keys): every TOML reader of the Python tools reads so.
    tomllib.TOMLDecodeError and RecursionError are the reader's to name;
    an integer of more digits than Python converts is a TOMLDecodeError
    too (tomllib lets int()'s ValueError through)."""
    text = check_toml_keys(path, text)
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError:
        raise
    except ValueError:
        limit = sys.get_int_max_str_digits()
        m = re.search(r"[0-9][0-9_]{%d,}" % limit, text)
        where = f" (at line {text.count(chr(10), 0, m.start()) + 1})" if m else ""
        raise tomllib.TOMLDecodeError(f"an integer of more than {limit} digits{where}") from None


def output_target(path):
    """Where an output at `path` is written, and how: ("replace", P) for a
    path that is absent or a regular file (a temporary beside P renamed
    over it), also when `path` is a symlink to one (P is then the link's
    target: the link stays, and a failed run leaves the target as it was);
    ("in place", path) for anything else (a device, a FIFO, a symlink to
    one), written and never unlinked."""
    try:
        st = os.stat(path)
    except FileNotFoundError:
        return ("replace", os.path.realpath(path) if os.path.islink(path) else path)
    except OSError:
        return ("in place", path)
    if stat.S_ISREG(st.st_mode):
        return ("replace", os.path.realpath(path) if os.path.islink(path) else path)
    return ("in place", path)


def check_standard_output(inputs):
    """Standard output takes a tool's report (or listing) whatever its
    outputs are: opened by the shell onto an input (what, path) (1<> or
    >>), it would be written into it. Refused, as GNU cat refuses it
    ("input file is output file")."""
    try:
        out = os.fstat(1)
    except OSError:
        return
    if not stat.S_ISREG(out.st_mode):
        return
    for what, path in inputs:
        try:
            st = os.stat(path) if path else None
        except OSError:
            continue
        if st is not None and (st.st_dev, st.st_ino) == (out.st_dev, out.st_ino):
            raise UsageError(f"{path}: standard output is {what}: what goes there would be written into it")


def check_outputs(inputs, outputs):
    """Before anything is opened: no output (option, path) names an input
    (what, path) or another output, as the same file (device and inode) or,
    for files that do not exist yet, the same path; none is a directory.
    Standard output ("-") may be one output only."""
    def ident(path):
        if path == "-":
            path = "/dev/stdout"
        try:
            st = os.stat(path)
            return ("file", st.st_dev, st.st_ino), st
        except OSError:
            return ("path", os.path.realpath(path)), None
    check_standard_output(inputs)
    taken = {}
    for what, path in inputs:
        if path:
            taken[ident(path)[0]] = what
    for option, path in outputs:
        if not path:
            continue
        key, st = ident(path)
        if st is not None and stat.S_ISDIR(st.st_mode):
            raise UsageError(f"{path}: cannot create: is a directory")
        # Opening a FIFO to write waits for a reader, for ever if none comes:
        # refused unless it is standard output ("-", /dev/stdout), which the
        # shell has opened already.
        if st is not None and (stat.S_ISFIFO(st.st_mode) or stat.S_ISSOCK(st.st_mode)) \
                and not to_standard_output([path]):
            raise UsageError(f"{option} {path}: cannot create: is {_kind(st.st_mode)}, not a regular file "
                             "(opening it would wait for a reader; - is standard output)")
        if key in taken:
            raise UsageError(f"{option} {path}: is also {taken[key]}")
        taken[key] = f"{option}'s output"


def to_standard_output(paths):
    """Whether one of `paths` is this process's standard output."""
    try:
        out = os.fstat(1)
    except OSError:
        return False
    for p in paths:
        if not p:
            continue
        if p == "-":
            return True
        try:
            st = os.stat(p)
        except OSError:
            continue
        if (st.st_dev, st.st_ino) == (out.st_dev, out.st_ino) and not stat.S_ISREG(st.st_mode) or \
                p in ("/dev/stdout", "/proc/self/fd/1"):
            return True
    return False


_temporaries = set()


def register_temporary(path):
    """A temporary file or folder of the run's: removed when the run ends,
    however (main_wrapper), and by remove_temporaries."""
    _temporaries.add(path)


def unregister_temporary(path):
    _temporaries.discard(path)


def _new_temporary(directory, prefix, make):
    """A new file or folder (`make(path)`) of an unpredictable name in
    `directory`, registered before it exists: a signal at any point of its
    making leaves nothing behind (one registered after it is made could be
    left, the signal taken in between)."""
    for _ in range(100):
        path = os.path.join(directory, prefix + secrets.token_hex(4))
        register_temporary(path)
        try:
            return make(path), path
        except FileExistsError:
            unregister_temporary(path)   # another's: not ours to remove
        except OSError:
            unregister_temporary(path)   # not made
            raise
    raise FileExistsError(errno.EEXIST, "no unused temporary name", directory)


def temporary_file(directory, prefix):
    """(fd, path) of a new file of the run's (temporaries, _new_temporary)."""
    return _new_temporary(directory, prefix,
                          lambda p: os.open(p, os.O_RDWR | os.O_CREAT | os.O_EXCL | os.O_CLOEXEC | os.O_NOCTTY, 0o600))


def temporary_folder(prefix):
    """The path of a new folder of the run's in the temporary folder
    (TMPDIR), as tempfile.mkdtemp's (temporaries, _new_temporary)."""
    return _new_temporary(tempfile.gettempdir(), prefix, lambda p: os.mkdir(p, 0o700))[1]


def remove_left_temporaries(path, since):
    """The temporaries a process killed outright (SIGKILL, a crash: no
    handler of its own ran) left beside `path`: `.NAME.` and a random tail
    (this module's temporaries and common/output_file.cpp's), regular files
    of ours made since `since` (time.time())."""
    if not path or path == "-":
        return
    d, base = os.path.dirname(path) or ".", os.path.basename(path)
    pattern = re.compile(re.escape(f".{base}.") + r"[A-Za-z0-9]{6,16}")
    try:
        names = os.listdir(d)
    except OSError:
        return
    for name in names:
        if pattern.fullmatch(name):
            p = os.path.join(d, name)
            try:
                st = os.lstat(p)
                if stat.S_ISREG(st.st_mode) and st.st_uid == os.getuid() and st.st_mtime >= since - 1:
                    os.unlink(p)
            except OSError:
                pass


def remove_temporaries():
    """Removes every registered temporary (files and folders); safe to call
    from another thread than the one running the tool."""
    for t in list(_temporaries):
        if os.path.isdir(t) and not os.path.islink(t):
            shutil.rmtree(t, ignore_errors=True)
        else:
            try:
                os.unlink(t)
            except OSError:
                pass
        _temporaries.discard(t)


def write_output(path, data, what="output", own=False):
    """Writes `data` (str or bytes) to `path` as rbcd-sim writes its outputs;
    `own`: a file of the tool's own in its output folder, always replaced
    through a temporary, whatever is at its name (a symlink, another name of
    a file, a FIFO: the name is given a new file, nothing is written
    through it)."""
    if isinstance(data, str):
        data = data.encode("utf-8")
    if os.path.isdir(path) and not (own and os.path.islink(path)):
        raise UsageError(f"{path}: cannot create: is a directory")
    how, target = ("replace", path) if own else output_target(path)
    if how == "in place":
        try:
            fd = os.open(path, os.O_WRONLY | os.O_NOCTTY | os.O_CLOEXEC)
        except OSError as e:
            raise UsageError(f"{path}: cannot create: {e.strerror}")
        try:
            _write_all(fd, data)
        except OSError as e:
            raise WriteError(f"{escape(path)}: write failed: {e.strerror}") from None
        finally:
            os.close(fd)
        return
    d, base = os.path.split(target)
    try:
        fd, tmp = temporary_file(d or ".", f".{base}.")
    except OSError as e:
        raise UsageError(f"{path}: cannot create: {e.strerror}")
    try:
        mask = os.umask(0)
        os.umask(mask)
        os.fchmod(fd, 0o666 & ~mask)
        _write_all(fd, data)
        os.close(fd)
        fd = -1
        os.replace(tmp, target)
    except BaseException as e:
        if fd >= 0:
            os.close(fd)
        try:
            os.unlink(tmp)
        except OSError:
            pass
        if isinstance(e, OSError):
            raise WriteError(f"{escape(path)}: write failed: {e.strerror}") from None
        raise
    finally:
        _temporaries.discard(tmp)


def _write_all(fd, data):
    view = memoryview(data)
    while view:
        n = os.write(fd, view)
        view = view[n:]


def same_file(a, b):
    try:
        sa, sb = os.stat(a), os.stat(b)
    except OSError:
        return False
    return (sa.st_dev, sa.st_ino) == (sb.st_dev, sb.st_ino)


def _interrupt(signum, _frame):
    raise KeyboardInterrupt


def main_wrapper(prog, fn, argv):
    """fn(argv) with the project's exit statuses: its return value; 2 and one line for
    UsageError; 1 and one line for WriteError and any other error; 130 when
    interrupted. Never a traceback."""
    release_signals()
    for s in (signal.SIGTERM, signal.SIGHUP):
        if kept(s):   # (SIGHUP ignored when the program started, nohup, stays ignored)
            signal.signal(s, _interrupt)
    try:
        return fn(argv)
    except UsageError as e:
        say(prog, str(e))
        return 2
    except WriteError as e:
        say(prog, str(e))
        return 1
    except KeyboardInterrupt:
        say(prog, "interrupted")
        return 130
    except RecursionError:
        say(prog, "input nested too deep to read (internal error)")
        return 1
    except MemoryError:
        say(prog, "out of memory (internal error)")
        return 1
    except Exception as e:   # noqa: BLE001: the promise is one line, whatever failed
        say(prog, f"internal error: {type(e).__name__}: {e}")
        return 1
    finally:
        ignore_signals()   # (done: a signal from here changes nothing)
        remove_temporaries()

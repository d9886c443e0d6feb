"""The reduced capture (--reduced-out): the calls of a capture that the
emulation reads, in order, as apitrace's reader yields them, pickled
(pointers as plain integers) into an xz stream after a header record.
Texture images, colours, texture coordinates, lighting and the like are left
out: they cannot change the unit's input (IGNORED_PREFIXES), so converting
the reduced capture gives the same outputs as converting the capture itself,
at a few per cent of its size: the game suite's committed form
(docs/games.md)."""
import io
import lzma
import os
import pickle

from .apitrace import MAX_RECORD_VALUES, CallReader, PointerType, call_values_within, too_many_values, where
from ..cli import U63
from .errors import ConvertError, printable
from .converter import STATE_UPDATES, Converter
from .gl_registry import registry
from .gl_tables import END_FRAME_CALLS, IGNORED_PREFIXES, base_name
from .glstate.framebuffers import texture_image_digest
from .glstate.texture_formats import DIGEST_TAG
from .glstate.texture_levels import PASSED_OVER_IMAGES
from .glstate.textures import REDUCED_TEXTURES
from .outputs import SafeText
from .window_registry import APITRACE_ONLY as WS_APITRACE_ONLY, PREFIXES, window_registry

REDUCED_HEADER = ("rbcd-reduced-capture", 5, 0)   # (the source's size: 0, none known)
# Versions read: 5 keeps the calls that give 1D, 3D and array textures
# their images (framebuffer completeness reads them: glstate.
# texture_levels), which 4 and earlier dropped. 4 names, in its header record ("rbcd-reduced-capture", 4,
# bytes), the size of the capture it was reduced from (the converter's
# bounds scale with it: source_bytes), and keeps the blend factors and draw
# buffers (glstate.color_outputs), which 3 and earlier dropped as changing
# no fragment. 3 carries, with a draw whose vertex shader reads 2D
# textures, the calls that made them (glstate.textures.REDUCED_TEXTURES);
# 2 and 1 were written before vertex shaders could read them. Version 1,
# written before glGenFramebuffers and glGenRenderbuffers were kept: the
# framebuffer and renderbuffer names it binds are taken as it binds them
# (shows_every_gen).
REDUCED_VERSIONS = (1, 2, 3, 4, 5)
# A reduced capture is credited with the size of its source capture, up to
# this many times its own: its header's claim cannot be checked, and the
# bounds it buys must stay of the file's own order (round 22's R22-6: a
# claim 1000 times an 11 KB file's size had bought 80 minutes of geometry
# shaders). A geometry-heavy capture reduces to about an eighth of its size.
REDUCED_SOURCE_CREDIT = 16
# A reduced capture expands to at most this many times its size (the game
# suite's expand 10 to 20 times; a file that expands more is refused before
# its memory is spent).
REDUCED_EXPANSION = 1000
REDUCED_END = "end"   # the last record, ("end", calls): a file cut anywhere lacks it
# Sent into read_calls' generator (capture.check_rest) when the converter
# has read the last frame it asks for.
CHECK_REST = object()
XZ_MAGIC = b"\xfd7zXZ\x00"
# Kept although the emulation passes over them: the window system (frame
# ends, the window's size), and glFrameTerminatorGREMEDY (END_FRAME_CALLS).
REDUCED_KEEP = ("glX", "egl", "wgl")
# Arguments a handled call carries that the emulation never reads whole:
# texture images (a texture's size is read, and its image's digest, which
# takes the pixels' place).
REDUCED_DROP = {"glTexImage2D": "pixels", "glTexSubImage2D": "pixels", "glCompressedTexImage2D": "data",
                "glCompressedTexSubImage2D": "data", "glTexImage2DMultisample": None,
                "glTextureSubImage2D": "pixels", "glCompressedTextureSubImage2D": "data",
                "glTextureImage2D": "pixels", "glTexImage1D": "pixels", "glTexImage3D": "pixels",
                "glCompressedTexImage1D": "data", "glCompressedTexImage3D": "data", "glTextureImage1D": "pixels",
                "glTextureImage3D": "pixels", "glTexImage3DMultisample": None}   # (and EXT_direct_state_access's)


# Read by the emulation for the depth check alone (which replays the capture
# itself, never a reduced one): left out, as they change no output.
REDUCED_CHECK_ONLY = {"glProvokingVertex"}


def reduced_keeps(name):
    """Whether the emulation reads the call for the outputs: it has a
    handler, starts Mesa's state update (STATE_UPDATES: a copy into a
    texture of another dimension), is not passed over (and is refused),
    gives texture images the converter does not follow (texture_levels:
    what follows is not computed), or is the window system's."""
    base = base_name(name)
    if base in REDUCED_CHECK_ONLY:
        return False
    return base in Converter.HANDLERS or base in STATE_UPDATES or not name.startswith(IGNORED_PREFIXES) \
        or PASSED_OVER_IMAGES.match(base) \
        or name.startswith(REDUCED_KEEP) or name in END_FRAME_CALLS


# Arguments of handled calls the emulation never reads: left out (None).
# Pixel rectangles are read for their size alone.
REDUCED_BLANK = {"glDrawPixels": "pixels", "glBitmap": "bitmap"}


def reduced_args(name, args):
    blank = REDUCED_BLANK.get(base_name(name))
    if blank is not None:
        return [(k, None if k == blank else plain_value(v)) for k, v in args]
    drop = REDUCED_DROP.get(base_name(name))
    if drop is None:
        return [(k, plain_value(v)) for k, v in args]
    digest = texture_image_digest(dict(args))
    kept = (DIGEST_TAG, digest) if digest else None
    return [(k, kept if k == drop else plain_value(v)) for k, v in args]


def plain_value(v):
    """A decoded argument without apitrace's pointer class (an int subclass)."""
    if isinstance(v, PointerType):
        return int(v)
    if isinstance(v, list):
        return [plain_value(x) for x in v]
    if isinstance(v, tuple):
        return tuple(plain_value(x) for x in v)
    if isinstance(v, dict):
        return {k: plain_value(x) for k, x in v.items()}
    return v


def is_reduced_capture(path):
    try:
        with open(path, "rb") as f:
            return f.read(len(XZ_MAGIC)) == XZ_MAGIC
    except OSError:
        return False


def writable(v):
    """repr(v), or what v is when Python will not write it (an integer of
    more than 4,300 digits inside it, nesting past the recursion limit)."""
    try:
        return repr(v)
    except (ValueError, RecursionError):
        return f"a {type(v).__name__} too large or deep to write"


def header_version(head):
    """The version a reduced capture's header record names (an int: True
    and 2.0 equal 1 and 2 in Python, and are no version), or None when the
    record is no such header; a version this converter does not read is
    the file's error."""
    version = head[1] if isinstance(head, tuple) and len(head) in (2, 3) and head[0] == REDUCED_HEADER[0] else None
    if version is not None and type(version) is not int:
        raise ConvertError(f"a reduced capture whose header's version, {printable(writable(version), 40)} "
                           f"({type(version).__name__}), is not a whole number")
    if version is not None and version not in REDUCED_VERSIONS:
        raise ConvertError(f"a reduced capture of version {printable(version, 40)}: this converter reads "
                           f"versions {', '.join(map(str, REDUCED_VERSIONS[:-1]))} and {REDUCED_VERSIONS[-1]}")
    if version is not None and (len(head) == 3) != (version >= 4):
        raise ConvertError(f"a reduced capture of version {version} whose header is not of that version")
    if version is not None and version >= 4 and not (type(head[2]) is int and 0 <= head[2] < 1 << 63):
        size = head[2] if type(head[2]) is int else writable(head[2])   # (printable names a long integer by its size)
        raise ConvertError(f"a reduced capture whose header gives its source's size as {printable(size, 40)}, "
                           "not a number of bytes")
    return version


def source_bytes(path):
    """The size the converter's bounds take for the capture at `path`: an
    apitrace capture's own; a reduced capture's source's, as its header
    names it (version 4), up to REDUCED_SOURCE_CREDIT times its own size,
    and at least its own (0 for a path that cannot be read: its reader
    names the error)."""
    try:
        size = os.path.getsize(path)
    except OSError:
        return 0
    if not is_reduced_capture(path):
        return size
    try:
        head = reduced_header(path)
        claimed = head[2] if (header_version(head) or 0) >= 4 else 0
    except ConvertError:
        claimed = 0   # (read_reduced_calls names the file's error)
    return max(size, min(claimed, REDUCED_SOURCE_CREDIT * size))


def reduced_header(path):
    """A reduced capture's header record, or None when it does not decode
    (read_reduced_calls then names the file's error)."""
    try:
        with open(path, "rb") as raw:
            return CallReader(io.BufferedReader(BoundedXz(raw, 1 << 20))).load()
    except (ConvertError, lzma.LZMAError, EOFError, OSError, pickle.UnpicklingError, ValueError, TypeError,
            AttributeError, IndexError, MemoryError, OverflowError, RecursionError):
        return None


class BoundedXz(io.RawIOBase):
    """An xz file read as a stream of at most `limit` decompressed bytes,
    one xz stream with nothing after it: a small file that expands without
    end, or bytes appended to a reduced capture, are the file's error."""

    def __init__(self, f, limit):
        self.f, self.limit, self.total = f, limit, 0
        self.z = lzma.LZMADecompressor(format=lzma.FORMAT_XZ)
        self.pending = b""

    def readable(self):
        return True

    def readinto(self, buf):
        while not self.pending:
            if self.z.eof:
                if self.z.unused_data or self.f.read(1):
                    raise ConvertError("bytes after the xz stream: not a reduced capture as written")
                return 0
            data = self.f.read(1 << 16) if self.z.needs_input else b""
            if self.z.needs_input and not data:
                raise EOFError("the xz stream is cut short")
            self.pending = self.z.decompress(data, max_length=1 << 20)
            self.total += len(self.pending)
            if self.total > self.limit:
                raise ConvertError(f"expands past {self.limit} bytes ({REDUCED_EXPANSION} times its size, the "
                                   "limit; docs/gl-capture.md)")
        n = min(len(buf), len(self.pending))
        buf[:n] = self.pending[:n]
        self.pending = self.pending[n:]
        return n


# A record as the writer pickles it (protocol 4): PROTO, then frames of at
# most 64 KiB and one opcode, and between them the payloads of 64 KiB or more
# (bytes, strings) the pickler writes outside frames. A frame of 1 MiB at
# most; past RECORD_UNCOUNTED_BYTES of frames in one record, each further
# frame's opcodes are counted before the unpickler reads them: each can make
# an object (an empty list: 80 bytes of memory from 1 byte), so a record's
# memory stays within about 0.3 GB whatever it holds, where a 10 KB file
# had made 5 GB of empty lists in one record.
PROTO, FRAME = 0x80, 0x95
UNFRAMED_LENGTH = {ord("B"): 4, ord("X"): 4, 0x8E: 8, 0x8D: 8, 0x96: 8}   # BINBYTES, BINUNICODE, *8, BYTEARRAY8
MAX_FRAME_BYTES = 1 << 20
RECORD_UNCOUNTED_BYTES = 1 << 20
RECORD_MAX_OPCODES = 3 << 20   # with MAX_RECORD_VALUES values a call carries, and their MARKs and memo


class RecordStream:
    """One record of a reduced capture for the unpickler, read from `f` as
    the writer frames it (above); anything else is the file's error, raised
    before the unpickler sees the bytes. The unpickler (C) reads an opcode
    outside a frame as 1 byte, a length whole, a frame or payload whole."""

    def __init__(self, f, no):
        self.f, self.no = f, no
        self.state, self.length = "proto", 0
        self.framed = self.opcodes = 0

    def fail(self, why):
        raise ConvertError(f"{where(self.no)}: the reduced capture does not decode ({why})")

    def take(self, n):
        b = self.f.read(n)
        if len(b) != n:
            raise EOFError("the reduced capture is cut short")
        return b

    def read(self, n):
        if self.state == "proto":   # PROTO 4: the record's first two bytes
            b = self.take(n)
            if n != 2 and n != 1 or b != bytes([PROTO, 4])[:n]:
                self.fail("a record that is not a pickle as the writer makes it")
            self.state = "proto arg" if n == 1 else "op"
            return b
        if self.state == "proto arg":
            self.state = "op"
            if n != 1 or self.take(1) != b"\x04":
                self.fail("a record that is not a pickle as the writer makes it")
            return b"\x04"
        if self.state == "op":
            op = self.take(1) if n == 1 else b""
            if op and op[0] == FRAME:
                self.state, self.length = "frame length", 8
            elif op and op[0] in UNFRAMED_LENGTH:
                self.state, self.length = "payload length", UNFRAMED_LENGTH[op[0]]
            else:
                self.fail("a record not framed as the writer frames it")
            return op
        if n != self.length:
            self.fail("a record not framed as the writer frames it")
        b = self.take(n)
        if self.state == "frame length":
            self.state, self.length = "frame", int.from_bytes(b, "little")
            if self.length > MAX_FRAME_BYTES:
                self.fail(f"a frame of {self.length} bytes, more than the writer makes")
        elif self.state == "payload length":
            self.state, self.length = "payload", int.from_bytes(b, "little")
            if self.length < 1 << 16:   # a smaller one is in a frame
                self.fail("a record not framed as the writer frames it")
            limit = getattr(self.f.raw, "limit", None)
            if limit is not None and self.length > limit:
                self.fail(f"a value of {self.length} bytes, more than the capture may expand to "
                          f"({REDUCED_EXPANSION} times its size, the limit; docs/gl-capture.md)")
        else:
            if self.state == "frame":
                self.count(b)
            self.state = "op"
        return b

    def count(self, frame):
        """A frame's opcodes counted (past the record's first
        RECORD_UNCOUNTED_BYTES of frames), before any is unpickled."""
        self.framed += len(frame)
        if self.framed <= RECORD_UNCOUNTED_BYTES:
            self.opcodes += len(frame)   # at most one opcode a byte
            return
        import pickletools
        try:
            for _ in pickletools.genops(frame):
                self.opcodes += 1
                if self.opcodes > RECORD_MAX_OPCODES:
                    self.fail(f"a record of more than {RECORD_MAX_OPCODES} pickle opcodes: more values than "
                              f"the {MAX_RECORD_VALUES} a call may carry")
        except ValueError:
            pass   # the frame ends within an opcode (the unpickler says how)

    def readinto(self, buf):
        """The unpickler's read. A payload goes straight into the
        unpickler's buffer (read(n) would hold a second copy of it while
        it is copied in)."""
        view = memoryview(buf).cast("B")
        if self.state == "payload" and len(view) == self.length:
            got = 0
            while got < len(view):
                n = self.f.readinto(view[got:])
                if not n:
                    raise EOFError("the reduced capture is cut short")
                got += n
            self.state = "op"
            return got
        b = self.read(len(view))
        view[:len(b)] = b
        return len(b)

    def readline(self):
        self.fail("a record not framed as the writer frames it")


def read_reduced_calls(path):
    last = None
    try:
        with open(path, "rb") as raw:
            size = os.fstat(raw.fileno()).st_size
            f = io.BufferedReader(BoundedXz(raw, REDUCED_EXPANSION * max(size, 1 << 16)))
            # A new unpickler for every record, as the writer pickles each on
            # its own: a record cannot name an earlier record's objects (one
            # 5.9 KB file made a gigabyte of copies of one blob through the memo).
            try:
                head = CallReader(RecordStream(f, None)).load()
            except EOFError:
                head = None
            if header_version(head) is None:
                raise ConvertError("an xz file that is not a reduced capture (rbcd-gl2rbt --reduced-out)")
            count = 0
            while True:
                try:
                    c = CallReader(RecordStream(f, last)).load()
                except EOFError:
                    raise ConvertError(f"{where(last)}: the reduced capture is cut short (no end record)")
                if isinstance(c, tuple) and len(c) == 2 and c[0] == REDUCED_END:
                    if c[1] != count or f.read(1):
                        raise ConvertError(f"{where(last)}: the reduced capture does not decode (bad end record)")
                    break
                count += 1
                if not (isinstance(c, tuple) and len(c) == 5 and isinstance(c[0], int) and not isinstance(c[0], bool)
                        and isinstance(c[1], str)
                        and isinstance(c[2], list) and isinstance(c[4], int)
                        and 0 <= c[0] <= U63[1] and (last is None or c[0] > last)):
                    raise ConvertError(f"{where(last)}: the reduced capture does not decode (unexpected record)")
                if not call_values_within(c):   # before anything walks its arguments
                    raise too_many_values(c[0])
                if not all(isinstance(x, tuple) and len(x) == 2 and isinstance(x[0], str) for x in c[2]) \
                        or len({x[0] for x in c[2]}) != len(c[2]):   # each argument named once, as apitrace's
                    raise ConvertError(f"{where(last)}: the reduced capture does not decode (unexpected record)")
                c = in_order(c)
                last = c[0]
                if (yield c) is CHECK_REST:
                    check_rest(f, count, last)
                    return
    except (lzma.LZMAError, EOFError, OSError, pickle.UnpicklingError, ValueError, TypeError, AttributeError,
            IndexError, MemoryError, OverflowError, RecursionError) as e:
        # (OverflowError: a length past 2^63 read by the unpickler itself.)
        raise ConvertError(f"{where(last)}: the reduced capture does not decode ({printable(e, 80)})")


def in_order(c):
    """The call with its arguments as apitrace writes them: the function's
    parameters (gl_registry, window_registry: apitrace's names, the
    prototype's order), each fixed-length array of its length. A record
    naming them in another order is put in order (handlers read some by
    position: an altered record with glOrtho's right before its left had
    been read as a mirrored projection; glXMakeCurrent's context is its
    last); one naming a parameter the function lacks or leaving one out,
    or an array of another length (glVertex3fv of two), is the reduced
    capture's error, as is a name starting as GL's or a window system's
    that no registry has (glDrawArraysARB, glXFrobnicateMESA, "glXMakeCurrent
    " with a space) but for the few apitrace records (APITRACE_ONLY).
    memcpy and other names of neither form are taken as they are (the
    converter refuses those it has no rule for)."""
    no, name, args = c[0], c[1], c[2]
    # (by prefix: a name of the form's start and anything after it, a
    # trailing space, other letters' case, is checked too, not passed over)
    if name.startswith(tuple(PREFIXES)) or name in WS_APITRACE_ONLY:
        params = window_registry().signature(name)
        if params is None:
            raise ConvertError(f"call {no}: {printable(name)} is no {PREFIXES.get(name[:3], 'window-system')} "
                               "function (neither its registry nor apitrace has one of that name)")
        sig = tuple((k, None, None, None) for k in params)
    elif name.startswith("gl"):
        sig = registry().signature(name)
        if sig is None:
            # (glDrawArraysARB had been drawn as glDrawArrays, its arguments unchecked)
            raise ConvertError(f"call {no}: {printable(name)} is no GL function (the registry has none of that name)")
    else:
        return c
    extra = args[-1:] if args and args[-1][0] == REDUCED_TEXTURES else []
    own = args[:len(args) - len(extra)]
    want = tuple(p[0] for p in sig)
    names = tuple(k for k, _ in own)
    if names != want:
        if sorted(names) != sorted(want):
            raise ConvertError(f"call {no}: {printable(name)}'s arguments are named ({printable(', '.join(names))}); "
                               f"apitrace writes ({', '.join(want)})")
        by_name = dict(own)
        own = [(k, by_name[k]) for k in want]
        c = (no, name, own + extra, c[3], c[4])
    for (k, v), p in zip(own, sig):
        if p[3] is not None and isinstance(v, (list, tuple)) and len(v) != p[3]:
            raise ConvertError(f"call {no}: {printable(name)}: the {k} holds {len(v)} values, not {p[3]}")
    return c


def check_rest(f, count, last):
    """The rest of a reduced capture the converter does not convert (--frames
    stops before its end): decompressed to the end of its xz stream (its
    checks: xz's checksums, its end, nothing after it; BoundedXz's expansion
    limit) without unpickling its records, and its last bytes the end
    record, of at least the `count` calls read. Costs about a tenth of a
    second for each 2 MB of the file (lzma), against whole seconds to
    convert a frame's calls."""
    tail = b""
    while True:
        b = f.read(1 << 20)
        if not b:
            break
        tail = (tail + b)[-64:]
    # The end record as the writer pickles it (protocol 4: PROTO, then one
    # FRAME of the given length, ending at the file's end).
    pos = tail.rfind(b"\x80\x04\x95")
    while pos >= 0:
        if pos + 11 + int.from_bytes(tail[pos + 3:pos + 11], "little") == len(tail):
            end = CallReader(io.BytesIO(tail[pos:])).load()
            if isinstance(end, tuple) and len(end) == 2 and end[0] == REDUCED_END and isinstance(end[1], int) \
                    and not isinstance(end[1], bool) and end[1] >= count:
                return
            break
        pos = tail.rfind(b"\x80\x04\x95", 0, pos)
    raise ConvertError(f"{where(last)}: the reduced capture is cut short or damaged after the frames converted "
                       "(no end record)")


class ReducedWriter:
    """--reduced-out: the calls the emulation reads, as it reads them."""

    def __init__(self, path, source_size=0):
        self.out = SafeText(path, binary=True)
        self.z = lzma.LZMACompressor(preset=6)
        self.pickler_buf = io.BytesIO()
        self.count = 0
        self.put(REDUCED_HEADER[:2] + (source_size,) if REDUCED_HEADER[1] >= 4 else REDUCED_HEADER)

    def put(self, rec):
        self.pickler_buf.seek(0)
        self.pickler_buf.truncate()
        pickle.dump(rec, self.pickler_buf, protocol=4)
        self.out.write(self.z.compress(self.pickler_buf.getvalue()))

    def call(self, c, textures=None):
        """Call `c` as the emulation reads it; `textures`: the calls that
        made the textures its vertex shader read (REDUCED_TEXTURES), when
        the reduced capture has not carried them yet."""
        if reduced_keeps(c[1]) and not (base_name(c[1]).startswith("glTexEnv")
                                        and dict(c[2]).get("target") != "GL_TEXTURE_FILTER_CONTROL"):
            # (glTexEnv's only state the emulation reads is the texture
            # unit's LOD bias; its shading modes, many a GL 1.x frame, not.)
            extra = [(REDUCED_TEXTURES, textures)] if textures else []
            self.put((c[0], c[1], reduced_args(c[1], c[2]) + extra, plain_value(c[3]), c[4]))
            self.count += 1

    def commit(self):
        self.put((REDUCED_END, self.count))
        self.out.write(self.z.flush())
        self.out.commit()

    def abandon(self):
        self.out.abandon()

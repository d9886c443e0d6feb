"""Buffer objects: their contents as the capture wrote them (glBufferData,
glBufferSubData, glCopyBufferSubData, and writes through a mapping, which
apitrace records as memcpy calls into the mapped range), their bindings to
targets and to indexed binding points. Each change gives the buffer a new
version, by which the shader path's vertex stage knows what Mesa's copy
lacks."""
import mmap

from ...cli import I32, I64, U32, integer
from ..errors import checked, fail_call, printable
from ..gl_tables import MAX_BUFFER_BYTES, MAX_BUFFER_BYTES_IN_ALL, base_name
from . import bitfield, enum_arg, generated_name
from .texture_formats import FORMAT_COMPONENTS, PACKED_BYTES, TYPE_BYTES

# The bits of glBufferStorage's flags and glMapBufferRange's access the
# converter reads.
STORAGE_BITS = {0x0040: "GL_MAP_PERSISTENT_BIT", 0x0100: "GL_DYNAMIC_STORAGE_BIT"}
BUFFER_USAGES = {f"GL_{f}_{a}" for f in ("STREAM", "STATIC", "DYNAMIC") for a in ("DRAW", "READ", "COPY")}
MAX_BINDINGS = 1024   # indexed binding points kept (llvmpipe has fewer: Mesa refuses the rest at a draw)
# The binding points the shader path hands Mesa or follows for it, as
# llvmpipe (Mesa 22.3) defines them: how many (GL_MAX_*_BUFFER_BINDINGS,
# GL_MAX_TRANSFORM_FEEDBACK_BUFFERS) and the alignment of a range's offset
# (GL_*_BUFFER_OFFSET_ALIGNMENT; 4 for transform feedback, whose size too,
# and for atomic counters, a counter's size). A call past either is
# GL_INVALID_VALUE there and changes nothing, neither the indexed binding nor
# the generic one (binding_ignored).
FEEDBACK_TARGET = "GL_TRANSFORM_FEEDBACK_BUFFER"
SHADER_BINDINGS = {"GL_UNIFORM_BUFFER": (90, 16), "GL_SHADER_STORAGE_BUFFER": (80, 16), FEEDBACK_TARGET: (4, 4),
                   "GL_ATOMIC_COUNTER_BUFFER": (16, 4)}
# The internal formats glClearBufferData takes (those of texture buffers,
# GL 4.6 table 8.16) and the bytes of one element of each.
CLEAR_FORMATS = {f"GL_{c}{bits}{kind}": len(c) * bits // 8
                 for c in ("R", "RG", "RGB", "RGBA") for bits in (8, 16, 32) for kind in ("", "F", "I", "UI")
                 if not (kind == "" and bits == 32) and not (kind == "F" and bits == 8)
                 and not (c == "RGB" and bits != 32)}


def storage(size):
    """Zeroed storage for a buffer: a large one as anonymous memory, whose
    pages cost nothing until written (a capture may declare a buffer of
    1 GiB with no data and fill a few kilobytes of it)."""
    return mmap.mmap(-1, size) if size >= 1 << 20 else bytearray(size)


def merge_extents(extents):
    """[start, end) extents, sorted and joined where they touch."""
    out = []
    for s, e in sorted(extents):
        if out and s <= out[-1][1]:
            out[-1] = (out[-1][0], max(out[-1][1], e))
        else:
            out.append((s, e))
    return out


def binding_ignored(target, index, buf, offset, size, feedback_active=False, dsa=False):
    """Whether Mesa 22.3 refuses binding buffer `buf` (0: none) at `index`
    of a SHADER_BINDINGS target, `size` None for glBindBufferBase: past the
    binding points, a range whose size is not positive (of a buffer, not of
    0, which unbinds) or whose offset is not aligned (0's too). Transform
    feedback adds its own rules (transformfeedback.c): nothing changes while
    the bound object is active, even paused, and a range's size is a
    multiple of 4 and its offset not negative (the direct state access form
    wants a positive size of 0 too). A negative offset of the other targets
    passes: a draw that would read before the buffer is refused
    (vertex_stage)."""
    count, align = SHADER_BINDINGS[target]
    if index >= count:
        return True
    if target == FEEDBACK_TARGET:
        return feedback_active or size is not None and bool(
            size % 4 or offset % 4 or offset < 0 or (size <= 0 and (buf or dsa)))
    return size is not None and bool((buf and size <= 0) or offset % align)


def is_buffer_target(target):
    return isinstance(target, str) and target.startswith("GL_") and target.endswith("_BUFFER")


def named(handler, **targets):
    """The direct-state-access form (GL 4.5) of a buffer call's handler:
    each parameter in `targets` names a buffer object, which the handler
    finds bound at a target of its own (named after no GL target) in place
    of the target parameter it reads. A name that is not a buffer object
    (0, or never bound nor made by glCreateBuffers) is GL_INVALID_OPERATION:
    the call does nothing."""
    def h(self, no, name, a, args):
        d = dict(args)
        pseudo = {}
        for k, (param, target_param) in enumerate(targets.items()):
            buf = checked(no, integer, d.get(param), f"{name}: the buffer", *U32)
            if buf not in self.s.buffer_objects:
                return
            pseudo[param] = (target_param, f"GL_NAMED_{k}_BUFFER", buf)
        args = [pseudo[k][:2] if k in pseudo else (k, v) for k, v in args]
        for _, target, buf in pseudo.values():
            self.s.bound[target] = buf
        try:
            handler(self, no, name, [v for _, v in args], args)
        finally:
            for _, target, _ in pseudo.values():
                self.s.bound.pop(target, None)
    return h


def fill_range(buf, start, end, value):
    """buf[start:end] = `value` repeated (the range a whole number of it),
    a piece of 16 MiB at most at a time: a clear of a large buffer makes
    no copy of its size."""
    piece = memoryview(value * max(1, (16 << 20) // len(value)))
    at = start
    while at < end:
        k = min(len(piece), end - at)
        buf[at:at + k] = piece[:k]
        at += k


class BufferCalls:
    """Buffer objects, bound by target (self.s.bound; the element array
    buffer is the bound vertex array object's) and by index
    (self.s.indexed[(target, index)] = (buffer, offset, size or None))."""

    def bound_buffer(self, no, name, target):
        if not is_buffer_target(target):
            fail_call(no, f"{name}: {printable(target)} is not a buffer target")
        return self.s.bound.get(target, 0)

    def new_version(self, b):
        """Buffer b's contents changed: Mesa's copy is given them again."""
        self.s.next_version += 1
        self.s.buffer_versions[b] = self.s.next_version

    def changed(self, no, name, b, start=0, end=None):
        """Buffer b changed in bytes [start, end) (all of it by default): a
        new version, and the extent added to those ever written (for a
        large buffer: what Mesa's copy is given; the rest stays zero). The
        bytes held in all buffers stay within MAX_BUFFER_BYTES_IN_ALL.
        Written whole, its bytes are the capture's again, whatever the GPU
        wrote into it before."""
        self.new_version(b)
        buf = self.s.buffers[b]
        end = len(buf) if end is None else end
        if start <= 0 and end >= len(buf):
            self.s.gpu_buffers.pop(b, None)
        if isinstance(buf, mmap.mmap) and end > start:
            ext = self.s.buffer_written.setdefault(b, [])
            ext.append((start, end))
            if len(ext) > 64:
                ext = self.s.buffer_written[b] = merge_extents(ext)
            held = min(len(buf), sum(e - s for s, e in ext))
        else:
            held = len(buf) if isinstance(buf, bytearray) else 0
        self.held_bytes(no, name, b, held)

    def held_bytes(self, no, name, b, held):
        """Buffer b now holds `held` bytes of memory (written pages): refused
        past MAX_BUFFER_BYTES_IN_ALL over all buffers, so that copies between
        buffers cannot grow memory out of proportion to the capture."""
        self.s.buffer_bytes_in_all += held - self.s.buffer_held.get(b, 0)
        self.s.buffer_held[b] = held
        if self.s.buffer_bytes_in_all > MAX_BUFFER_BYTES_IN_ALL:
            fail_call(no, f"{name}: the buffers would hold more than {MAX_BUFFER_BYTES_IN_ALL >> 30} GiB of data "
                      "in all (docs/gl-capture.md, limits)")

    def gpu_wrote_buffer(self, no, b, how):
        """Buffer b's contents were written by the GPU (call `no`, `how`):
        not in the capture, so a later draw that reads them as vertex,
        index, command or vertex-shader data is refused (checked_buffer)."""
        if b and b in self.s.buffers:
            self.s.gpu_buffers[b] = (no, how)

    def checked_buffer(self, no, name, b, what):
        """Buffer b's data for a draw that reads it as `what`; refused if
        the GPU wrote it (its contents are not in the capture)."""
        wrote = self.s.gpu_buffers.get(b)
        if wrote is not None and wrote[0] != no:   # (a draw reads what it finds, before its own stores)
            fail_call(no, f"{printable(name)} reads {what} from buffer {b}, which the GPU wrote at call {wrote[0]} "
                      f"({printable(wrote[1])}): its contents are not in the capture; not emulated")
        return self.s.buffers.get(b)

    def h_pack_read(self, no, name, a, args):
        """glReadPixels, glGetTexImage and their kin: with a pixel pack
        buffer bound, the GPU writes the pixels into it."""
        b = self.s.bound.get("GL_PIXEL_PACK_BUFFER", 0)
        if not b:
            return
        d = dict(args)
        if base_name(name) in ("glReadPixels", "glReadnPixels"):
            # What GL refuses writes nothing: no pixel (a size of 0 or
            # less), or fewer bytes past the offset than the pixels take
            # packed as tightly as any pack state packs them.
            w, h, at = d.get("width"), d.get("height"), d.get("pixels", d.get("data"))
            fmt, kind = d.get("format"), d.get("type")
            pixel = PACKED_BYTES.get(kind) or FORMAT_COMPONENTS.get(fmt, 0) * TYPE_BYTES.get(kind, 0)
            if all(isinstance(v, int) and not isinstance(v, bool) for v in (w, h, at)) and pixel and \
                    (w <= 0 or h <= 0 or at < 0 or at + w * h * pixel > len(self.s.buffers.get(b, b""))):
                return
        self.gpu_wrote_buffer(no, b, f"{base_name(name)} into the pixel pack buffer")

    def h_query_result(self, no, name, a, args):
        """glGetQueryObject* with a query buffer bound, glGetQueryBufferObject*:
        the GPU writes the query's result into the buffer."""
        if "BufferObject" in name:
            b = dict(args).get("buffer")
            if isinstance(b, int) and not isinstance(b, bool):
                self.gpu_wrote_buffer(no, b, f"{base_name(name)} writes a query's result")
        else:
            b = self.s.bound.get("GL_QUERY_BUFFER", 0)
            if b:
                self.gpu_wrote_buffer(no, b, f"{base_name(name)} into the query buffer")

    def written_extents(self, b):
        """The [start, end) extents of buffer b that may hold non-zero bytes."""
        buf = self.s.buffers[b]
        if isinstance(buf, mmap.mmap):
            return merge_extents(self.s.buffer_written.get(b, []))
        return [(0, len(buf))]

    def h_bind_buffer(self, no, name, a, args):
        d = dict(args)
        target = d["target"]
        buf = checked(no, integer, d["buffer"], f"{name}: the buffer", *U32)
        if not is_buffer_target(target):
            return   # GL_INVALID_ENUM: the call does nothing
        if not self.generated(buf):
            return   # GL_INVALID_OPERATION: a core profile binds only generated names
        self.s.bound[target] = buf
        if buf:
            self.s.buffer_objects.add(buf)

    def generated(self, buf):
        """Whether a core profile takes `buf` as a buffer name (generated_name)."""
        return generated_name(self.core, self.s.buffer_names, buf)

    def h_gen_buffers(self, no, name, a, args):
        """glGenBuffers: names, whose objects exist once bound;
        glCreateBuffers: objects at once (direct state access)."""
        names = dict(args).get("buffers")
        if not isinstance(names, list):
            return   # apitrace recorded no names (a negative count: GL_INVALID_VALUE)
        if dict(args).get("n") != len(names):
            fail_call(no, f"{name}: {len(names)} names, not its count ({printable(dict(args).get('n'), 40)})")
        if self.s.buffer_names is None:
            self.s.buffer_names = set()
        for b in names:
            self.s.buffer_names.add(checked(no, integer, b, f"{name}: a buffer name", *U32))
            if base_name(name) == "glCreateBuffers" and b:
                self.s.buffer_objects.add(b)

    def h_bind_buffer_base(self, no, name, a, args):
        d = dict(args)
        target = d["target"]
        index = checked(no, integer, d["index"], f"{name}: the index", *U32)
        buf = checked(no, integer, d["buffer"], f"{name}: the buffer", *U32)
        offset = checked(no, integer, d.get("offset", 0), f"{name}: the offset", *I64)
        size = d.get("size")
        if size is not None:
            size = checked(no, integer, size, f"{name}: the size", *I64)
        if target in SHADER_BINDINGS:
            if binding_ignored(target, index, buf, offset, size, feedback_active=self.s.feedback[1]) \
                    or not self.generated(buf):
                return   # GL_INVALID_VALUE or GL_INVALID_OPERATION: the earlier binding stays
        elif not is_buffer_target(target) or index >= MAX_BINDINGS or offset < 0 or (size is not None and size <= 0) \
                or not self.generated(buf):
            return   # GL_INVALID_ENUM, GL_INVALID_VALUE or GL_INVALID_OPERATION: the call does nothing
        self.s.bound[target] = buf   # glBindBufferBase and Range also bind the generic target
        self.s.indexed[(target, index)] = (buf, offset, size)
        if buf:
            self.s.buffer_objects.add(buf)

    def h_bind_buffers(self, no, name, a, args):
        """glBindBuffersBase and glBindBuffersRange (GL 4.4): glBindBufferBase
        or Range at each index from first (NULL buffers: unbind them), with
        the generic binding left as it was; past the target's bindings the
        whole call does nothing (GL_INVALID_OPERATION), and an entry GL
        refuses is skipped."""
        d = dict(args)
        target = d.get("target")
        first = checked(no, integer, d.get("first"), f"{name}: first", *U32)
        count = checked(no, integer, d.get("count"), f"{name}: count", *I32)
        limit = SHADER_BINDINGS[target][0] if target in SHADER_BINDINGS else MAX_BINDINGS
        if count < 0 or first + count > limit or (target == FEEDBACK_TARGET and self.s.feedback[1]):
            return
        lists = {}
        for key in ("buffers",) + (("offsets", "sizes") if "Range" in name else ()):
            v = d.get(key)
            if v is None or v == 0 and not isinstance(v, bool):   # NULL, as apitrace records it
                v = [0] * count
            if not isinstance(v, list) or len(v) < count:
                fail_call(no, f"{name}: fewer {key} than its count")
            lists[key] = v
        generic = self.s.bound.get(target)
        for i in range(count):
            buf = lists["buffers"][i]
            if buf and (not isinstance(buf, int) or buf not in self.s.buffer_objects):
                continue   # no such buffer (a multi-bind creates none): GL_INVALID_OPERATION, the binding stays
            one = [("target", target), ("index", first + i), ("buffer", buf)]
            if "Range" in name and buf:
                one += [("offset", lists["offsets"][i]), ("size", lists["sizes"][i])]
            self.h_bind_buffer_base(no, name, [v for _, v in one], one)
        if generic is None:
            self.s.bound.pop(target, None)
        else:
            self.s.bound[target] = generic

    def h_buffer_data(self, no, name, a, args):
        d = dict(args)
        target = enum_arg(d.get("target"), no, f"{name}: the target")
        size = checked(no, integer, d.get("size", 0), f"{name}: the size", *I64)
        usage = enum_arg(d.get("usage", "GL_STATIC_DRAW"), no, f"{name}: the usage")
        # What GL ignores, in Mesa's order of checks: the target, a negative
        # size, the usage (GL_INVALID_ENUM, GL_INVALID_VALUE), no buffer
        # bound (GL_INVALID_OPERATION).
        if not is_buffer_target(target) or size < 0 or usage not in BUFFER_USAGES:
            return
        b = self.s.bound.get(target, 0)
        if not b or b in self.s.immutable_buffers:
            return   # GL_INVALID_OPERATION: no buffer, or glBufferStorage's
        if size > MAX_BUFFER_BYTES:
            fail_call(no, f"{name}: {size} bytes, more than a buffer's {MAX_BUFFER_BYTES} (docs/gl-capture.md, limits)")
        data = d.get("data")
        if data is not None and not isinstance(data, (bytes, bytearray)) and not (isinstance(data, int)
                                                                               and not isinstance(data, bool)):
            fail_call(no, f"{name}: the data is neither bytes, NULL nor an address apitrace recorded")
        buf = storage(size)
        written = 0
        if isinstance(data, (bytes, bytearray)):
            if len(data) != size:
                # apitrace records the size's bytes: another length is a
                # capture cut or altered.
                fail_call(no, f"{name}: {len(data)} bytes of data, not its size ({size})")
            buf[:] = data[:size]
            written = size
        self.s.buffers[b] = buf
        self.s.gpu_buffers.pop(b, None)   # new storage: what the capture gives
        if isinstance(buf, mmap.mmap):
            self.s.buffer_written[b] = []
        else:
            self.s.buffer_written.pop(b, None)
        self.changed(no, name, b, 0, written)

    def h_buffer_storage(self, no, name, a, args):
        """glBufferStorage (GL 4.4, EXT in ES): immutable storage, otherwise
        as glBufferData; of size 0 or less, GL_INVALID_VALUE."""
        d = dict(args)
        size = checked(no, integer, d.get("size", 0), f"{name}: the size", *I64)
        target = enum_arg(d.get("target"), no, f"{name}: the target")
        b = self.s.bound.get(target, 0) if is_buffer_target(target) else 0
        if size <= 0 or not b or b in self.s.immutable_buffers:
            return
        self.h_buffer_data(no, name, a, [("target", target), ("size", size), ("data", d.get("data")),
                                         ("usage", "GL_STATIC_DRAW")])
        flags, _ = bitfield(d.get("flags", 0), no, f"{name}: the flags", STORAGE_BITS)
        self.s.immutable_buffers[b] = "GL_DYNAMIC_STORAGE_BIT" in flags

    def h_buffer_sub_data(self, no, name, a, args):
        d = dict(args)
        b = self.bound_buffer(no, name, d.get("target"))
        buf = self.s.buffers.get(b)
        off, size, data = d.get("offset", 0), d.get("size", 0), d.get("data")
        if not isinstance(off, int) or not isinstance(size, int) or not isinstance(data, (bytes, bytearray)) \
                or len(data) != max(size, 0):
            fail_call(no, f"{name}: malformed arguments (offset, size or data: apitrace records the size's bytes)")
        if buf is None or off < 0 or size < 0 or off + size > len(buf) or self.s.immutable_buffers.get(b) is False:
            # GL_INVALID_VALUE or GL_INVALID_OPERATION (immutable storage
            # without GL_DYNAMIC_STORAGE_BIT): the call does nothing
            return
        buf[off:off + size] = data[:size]
        self.changed(no, name, b, off, off + size)

    def h_copy_buffer_sub_data(self, no, name, a, args):
        d = dict(args)
        src = self.s.buffers.get(self.bound_buffer(no, name, d.get("readTarget")))
        wb = self.bound_buffer(no, name, d.get("writeTarget"))
        dst = self.s.buffers.get(wb)
        ro, wo, size = d.get("readOffset"), d.get("writeOffset"), d.get("size")
        if not all(isinstance(v, int) and not isinstance(v, bool) for v in (ro, wo, size)):
            fail_call(no, f"{name}: the offsets and size are not integers")
        rb = self.bound_buffer(no, name, d.get("readTarget"))
        if src is None or dst is None or min(ro, wo, size) < 0 or ro + size > len(src) or wo + size > len(dst) \
                or (rb == wb and ro < wo + size and wo < ro + size):
            return   # GL_INVALID_VALUE or GL_INVALID_OPERATION (also overlapping ranges of one buffer): nothing
        # Only the source's written extents are copied (the rest is zero);
        # the destination's bytes the copy zeroes are zeroed where they may
        # hold data, so that a copy out of storage never written takes no
        # memory.
        pieces = [(max(s, ro), min(e, ro + size)) for s, e in self.written_extents(rb) if s < ro + size and e > ro]
        pieces = [(s - ro + wo, e - ro + wo, bytes(src[s:e])) for s, e in pieces if e > s]
        at, held = wo, self.written_extents(wb)
        for s, e, _ in pieces + [(wo + size, wo + size, b"")]:
            for zs, ze in held:
                lo, hi = max(zs, at), min(ze, s)
                if lo < hi:
                    dst[lo:hi] = bytes(hi - lo)
            at = e
        gpu = self.s.gpu_buffers.get(rb)
        for s, e, data in pieces:
            dst[s:e] = data
            self.changed(no, name, wb, s, e)
        self.new_version(wb)
        if gpu is not None:
            self.gpu_wrote_buffer(no, wb, f"{base_name(name)} from buffer {rb}, which the GPU wrote at call "
                                          f"{gpu[0]}")
        elif wo == 0 and size == len(dst):
            self.s.gpu_buffers.pop(wb, None)   # all of it the capture's bytes again

    def h_clear_buffer_data(self, no, name, a, args):
        """glClearBufferData and glClearBufferSubData (GL 4.3): the range
        filled with one element of the internal format, the value (NULL:
        zero) converted as Mesa converts it. What GL refuses changes
        nothing: a format or type Mesa refuses, a range outside the buffer
        or not a whole number of elements, a mapped buffer."""
        d = dict(args)
        b = self.bound_buffer(no, name, d.get("target"))
        buf = self.s.buffers.get(b)
        whole = "SubData" not in name
        off = 0 if whole else checked(no, integer, d.get("offset"), f"{name}: the offset", *I64)
        size = (len(buf) if buf is not None else 0) if whole else \
            checked(no, integer, d.get("size"), f"{name}: the size", *I64)
        internal, data = d.get("internalformat"), d.get("data")
        if isinstance(data, int) and not isinstance(data, bool) and data == 0:
            data = None   # NULL, as apitrace records it: zeros
        if data is not None and not isinstance(data, (bytes, bytearray)):
            fail_call(no, f"{name}: the data is neither bytes nor NULL")
        n = CLEAR_FORMATS.get(internal)
        if n is None and isinstance(internal, str) and internal.startswith(("GL_ALPHA", "GL_LUMINANCE",
                                                                            "GL_INTENSITY")):
            fail_call(no, f"{name}: {internal}, a texture buffer format of the compatibility profile only: "
                      "not emulated")
        if buf is None or n is None or off < 0 or size < 0 or off + size > len(buf) or b in self.s.mappings \
                or off % n or size % n or size == 0:
            return   # GL_INVALID_ENUM, _VALUE or _OPERATION, or nothing to clear
        fmt, kind = d.get("format"), d.get("type")
        pixel = PACKED_BYTES.get(kind) or FORMAT_COMPONENTS.get(fmt, 0) * TYPE_BYTES.get(kind, 0)
        if data is not None and pixel and len(data) != pixel:
            # apitrace records one pixel of the format and type: another
            # length is a capture cut or altered.
            fail_call(no, f"{name}: {len(data)} bytes of data, not one {printable(fmt)} pixel of "
                      f"{printable(kind)} ({pixel})")
        value = self.vertex_stage().clear_element(internal, fmt, kind, data, n)
        if value is None:
            return   # Mesa refuses the format and type (GL_INVALID_ENUM or _OPERATION): nothing changes
        if off == 0 and size == len(buf):
            self.s.gpu_buffers.pop(b, None)   # all of it is the capture's value again
        if not any(value) and isinstance(buf, mmap.mmap):
            # Zeros into storage whose pages cost nothing until written:
            # only what was written is zeroed.
            for s, e in self.written_extents(b):
                if s < off + size and e > off:
                    fill_range(buf, max(s, off), min(e, off + size), b"\0")
            self.new_version(b)
            return
        held = self.s.buffer_held.get(b, 0)
        if isinstance(buf, mmap.mmap) and self.s.buffer_bytes_in_all - held + min(len(buf), held + size) > \
                MAX_BUFFER_BYTES_IN_ALL:
            self.held_bytes(no, name, b, min(len(buf), held + size))   # refused before writing
        fill_range(buf, off, off + size, value)
        self.changed(no, name, b, off, off + size)

    def h_invalidate_buffer(self, no, name, a, args):
        """glInvalidateBufferData and glInvalidateBufferSubData (GL 4.3):
        the bytes are undefined from then on; all of them invalidated, what
        the GPU wrote there is gone, and the buffer is the capture's again
        (the bytes the converter holds are as good as any). What GL refuses
        (no such buffer, a range outside it) changes nothing."""
        d = dict(args)
        b = checked(no, integer, d.get("buffer"), f"{name}: the buffer", *U32)
        buf = self.s.buffers.get(b)
        if buf is None:
            return
        if "SubData" in name:
            off = checked(no, integer, d.get("offset"), f"{name}: the offset", *I64)
            length = checked(no, integer, d.get("length"), f"{name}: the length", *I64)
            if off != 0 or length != len(buf):
                return   # GL_INVALID_VALUE, or a part: what the GPU wrote beside it stays
        self.s.gpu_buffers.pop(b, None)

    def h_map_buffer(self, no, name, a, args):
        d = dict(args)
        access, _ = bitfield(d.get("access", ()), no, f"{name}: the access", STORAGE_BITS)
        if "GL_MAP_PERSISTENT_BIT" in access:
            fail_call(no, f"{name}: a persistent mapping, whose writes apitrace does not record as it "
                      "records other mapped writes: not emulated")
        b = self.bound_buffer(no, name, d.get("target"))
        buf = self.s.buffers.get(b)
        ptr = self.ret
        if type(ptr) is int and ptr == 0:
            # NULL: a mapping GL refused (past the buffer's data, a buffer
            # with no data store, one mapped already) maps nothing.
            return
        offset, length = d.get("offset", 0), d.get("length")
        if buf is None:
            fail_call(no, f"{name} of a buffer that holds no data")
        if length is None:
            length = len(buf) - offset
        if not isinstance(offset, int) or not isinstance(length, int) or offset < 0 or length < 0 \
                or offset + length > len(buf):
            fail_call(no, f"{name}: the range is outside the buffer's data")
        if isinstance(ptr, int) and ptr:
            self.s.mappings[b] = (ptr, offset, length)
            if "GL_MAP_INVALIDATE_BUFFER_BIT" in access or "GL_MAP_INVALIDATE_RANGE_BIT" in access and \
                    offset == 0 and length == len(buf):
                # Every byte the GPU wrote is undefined now: what the
                # capture writes through the mapping, or nothing GL defines.
                self.s.gpu_buffers.pop(b, None)

    def h_unmap_buffer(self, no, name, a, args):
        self.s.mappings.pop(self.bound_buffer(no, name, dict(args).get("target")), None)

    def h_memcpy(self, no, name, a, args):
        """apitrace's record of what the application wrote into a mapping."""
        d = dict(args)
        dest, src, n = d.get("dest"), d.get("src"), d.get("n")
        if not isinstance(dest, int) or not isinstance(src, (bytes, bytearray)) or n != len(src):
            fail_call(no, "memcpy: not a write into a mapping apitrace recorded (its n is not its data's length)")
        for b, (ptr, offset, length) in self.s.mappings.items():
            if ptr <= dest and dest + len(src) <= ptr + length:
                at = offset + dest - ptr
                self.s.buffers[b][at:at + len(src)] = src
                self.changed(no, name, b, at, at + len(src))
                return
        fail_call(no, "memcpy into memory that is not a mapped buffer's")

    def keep_for_holders(self, b):
        """A buffer deleted while a vertex array object that is not bound
        holds it, or while a buffer texture holds it (glTexBuffer, bound or
        not), lives on for them (GL 4.5, 5.1.2 and 5.1.3; Mesa draws it):
        its data moves to a name no call can give, which they take; the
        bound vertex array object lets it go, as GL detaches it there. A
        buffer texture's buffer with no data store yet moves too, so that
        a new buffer of the name is not the texture's."""
        current = self.current_vao()
        holders = [v for v in self.s.vaos.values() if v is not current and
                   (v.element == b or any(p.buffer == b for p in v.bindings.values()))] \
            if b in self.s.buffers else []
        for p in current.bindings.values():
            if p.buffer == b:
                p.buffer = 0
        textures = [t for t, (_, buf, _, _) in self.s.texture_buffers.items() if buf == b] if b else []
        if not holders and not textures:
            return
        self.s.next_version += 1
        kept = ("deleted", b, self.s.next_version)
        if b in self.s.buffers:
            self.s.buffers[kept] = self.s.buffers[b]
            self.s.buffer_versions[kept] = self.s.buffer_versions.get(b)
            if b in self.s.buffer_written:
                self.s.buffer_written[kept] = self.s.buffer_written[b]
            self.s.buffer_held[kept] = self.s.buffer_held.get(b, 0)
            self.s.buffer_bytes_in_all += self.s.buffer_held[kept]
        for v in holders:
            if v.element == b:
                v.element = kept
            for p in v.bindings.values():
                if p.buffer == b:
                    p.buffer = kept
        for t in textures:
            fmt, _, offset, size = self.s.texture_buffers[t]
            self.s.texture_buffers[t] = (fmt, kept, offset, size)

    def h_delete_buffers(self, no, name, a, args):
        d = dict(args)
        for b in d.get("buffers") or []:
            if isinstance(b, int):
                if self.s.buffer_names is not None:
                    self.s.buffer_names.discard(b)
                self.s.buffer_objects.discard(b)
                self.keep_for_holders(b)
                self.s.buffers.pop(b, None)
                self.s.buffer_versions.pop(b, None)
                self.s.buffer_written.pop(b, None)
                self.s.immutable_buffers.pop(b, None)
                self.held_bytes(no, name, b, 0)
                self.s.buffer_held.pop(b, None)
                self.s.mappings.pop(b, None)
                self.s.gpu_buffers.pop(b, None)
                for t, v in self.s.bound.items():
                    if v == b:
                        self.s.bound[t] = 0
                for k, (v, _, _) in list(self.s.indexed.items()):
                    # (Mesa unbinds a transform feedback binding point by
                    # glBindBufferBase, GL_INVALID_OPERATION while the bound
                    # object is active: the deleted buffer stays bound there.)
                    if v == b and not (k[0] == FEEDBACK_TARGET and self.s.feedback[1]):
                        self.s.indexed[k] = (0, 0, None)   # unbound, also in Mesa's copy an earlier draw bound

    HANDLERS = {
        "glBindBuffer": h_bind_buffer,
        "glGenBuffers": h_gen_buffers,
        "glCreateBuffers": h_gen_buffers,
        "glNamedBufferData": named(h_buffer_data, buffer="target"),
        "glNamedBufferSubData": named(h_buffer_sub_data, buffer="target"),
        "glNamedBufferStorage": named(h_buffer_storage, buffer="target"),
        "glCopyNamedBufferSubData": named(h_copy_buffer_sub_data, readBuffer="readTarget", writeBuffer="writeTarget"),
        "glClearNamedBufferData": named(h_clear_buffer_data, buffer="target"),
        "glClearNamedBufferSubData": named(h_clear_buffer_data, buffer="target"),
        "glMapNamedBuffer": named(h_map_buffer, buffer="target"),
        "glMapNamedBufferRange": named(h_map_buffer, buffer="target"),
        "glUnmapNamedBuffer": named(h_unmap_buffer, buffer="target"),
        "glBindBufferBase": h_bind_buffer_base,
        "glBindBufferRange": h_bind_buffer_base,
        "glBindBuffersBase": h_bind_buffers,
        "glBindBuffersRange": h_bind_buffers,
        "glBufferData": h_buffer_data,
        "glBufferSubData": h_buffer_sub_data,
        "glInvalidateBufferData": h_invalidate_buffer,
        "glInvalidateBufferSubData": h_invalidate_buffer,
        "glBufferStorage": h_buffer_storage,
        "glCopyBufferSubData": h_copy_buffer_sub_data,
        "glClearBufferData": h_clear_buffer_data,
        "glClearBufferSubData": h_clear_buffer_data,
        "glMapBuffer": h_map_buffer,
        "glMapBufferRange": h_map_buffer,
        "glUnmapBuffer": h_unmap_buffer,
        "memcpy": h_memcpy,
        "glDeleteBuffers": h_delete_buffers,
    } | dict.fromkeys(("glReadPixels", "glReadnPixels", "glGetTexImage", "glGetnTexImage", "glGetTextureImage",
                       "glGetnTextureImage", "glGetTextureSubImage", "glGetCompressedTexImage",
                       "glGetnCompressedTexImage", "glGetCompressedTextureImage", "glGetCompressedTextureSubImage"),
                      h_pack_read) \
      | dict.fromkeys([f"glGetQuery{o}Object{t}" for o in ("", "Buffer") for t in ("iv", "uiv", "i64v", "ui64v")],
                      h_query_result)

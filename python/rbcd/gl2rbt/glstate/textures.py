"""Texture images and sampler objects that a vertex shader may read.

A vertex shader that samples a 2D texture (a height map, a displacement, a
skinning palette stored as an image) needs its images in Mesa. The capture
holds them as the calls that made them, so each 2D texture keeps those
calls (glTexImage2D, glTexSubImage2D, glTexStorage2D, their compressed
forms, glTexParameter*, glGenerateMipmap, each with the pixel unpack state
it was made under), and the vertex stage replays them into Mesa when a
draw's vertex shader reads the texture (vertex_stage.py): Mesa then
computes what the driver computed, errors included. Sampler objects keep
their parameters the same way.

Memory stays in proportion to what the textures hold now, not to the
capture's length: an image call drops the earlier calls it overwrites (a
level defined again, a rectangle written again, storage given, a parameter
set again) when GL certainly takes it (texture_formats: one GL may refuse
must not take a valid one's place; Mesa judges it when the calls are
replayed), and the images kept in all textures are capped
(MAX_TEXTURE_BYTES_KEPT). A
texture that cannot be given to Mesa keeps the reason, and a draw whose
vertex shader reads it is refused naming it: its image rendered by the GPU
(a framebuffer attachment, glCopyTexImage2D), read from a pixel unpack
buffer, or over the cap."""
import math

from ...cli import I32, U32, U63, integer
from ..errors import ToolError, checked, fail_call, printable
from ..gl_tables import base_name
from . import gl_boolean, number, parameter_value
from .framebuffers import MAX_TEXTURE_UNITS, FramebufferCalls
from .texture_formats import (FORMAT_COMPONENTS, IMAGE_FORMATS, MAX_LEVEL, PACKED_BYTES, TYPE_BYTES, certain_level,
                              certain_mipmaps, certain_part, certain_storage, level_size_fits, refused_level,
                              refused_part, refused_storage, whole)

VERTEX_TEXTURE_TARGET = "GL_TEXTURE_2D"
MULTISAMPLE_TARGETS = ("GL_TEXTURE_2D_MULTISAMPLE", "GL_TEXTURE_2D_MULTISAMPLE_ARRAY")
GL_TEXTURE_SAMPLES = 0x9106
GL_TEXTURE_IMMUTABLE_LEVELS = 0x82DF
# The default texture (name 0) of a target other than 2D, as the converter
# names it beside the 2D one's calls: this plus the target's value.
DEFAULT_TEXTURE_BASE = 1 << 32
# GL_TEXTURE_SWIZZLE_R, _G, _B and _A.
SWIZZLE_PARAMETERS = (0x8E42, 0x8E43, 0x8E44, 0x8E45)
# The default buffer texture's (name 0 at GL_TEXTURE_BUFFER), whose buffer
# glTexBuffer may set as any other's.
DEFAULT_BUFFER_TEXTURE = DEFAULT_TEXTURE_BASE + 0x8C2A
# Image units are asked of Mesa's replay as texture units from here on.
IMAGE_UNIT_BASE = 1 << 16
# The argument a reduced capture adds to a draw whose vertex shader reads
# textures: [(texture, [(call, name, arguments, unpack state)])], the calls
# that made each texture as the converter keeps them (the reduced capture
# keeps no texture image otherwise).
REDUCED_TEXTURES = "rbcd-vertex-textures"
MAX_IMAGE_UNITS = 192                # llvmpipe's GL_MAX_IMAGE_UNITS
IMAGE_ACCESS = ("GL_READ_ONLY", "GL_WRITE_ONLY", "GL_READ_WRITE")
MAX_TEXTURE_BYTES_KEPT = 1 << 30     # pixels kept in all textures (docs/gl-capture.md, limits)
MAX_TEXTURE_CALLS_KEPT = 4096        # calls kept for one texture
UNPACK_PARAMETERS = ("GL_UNPACK_SWAP_BYTES", "GL_UNPACK_LSB_FIRST", "GL_UNPACK_ROW_LENGTH", "GL_UNPACK_SKIP_ROWS",
                     "GL_UNPACK_SKIP_PIXELS", "GL_UNPACK_ALIGNMENT", "GL_UNPACK_IMAGE_HEIGHT",
                     "GL_UNPACK_SKIP_IMAGES")
UNPACK_DEFAULTS = {"GL_UNPACK_ALIGNMENT": 4}
# The calls that define a level's image (a whole one) or part of it.
LEVEL_CALLS = ("glTexImage2D", "glCompressedTexImage2D")
PART_CALLS = ("glTexSubImage2D", "glCompressedTexSubImage2D")
PARAMETER_CALLS = ("glTexParameteri", "glTexParameterf", "glTexParameteriv", "glTexParameterfv",
                   "glTexParameterIiv", "glTexParameterIuiv")
KEPT_CALLS = LEVEL_CALLS + PART_CALLS + PARAMETER_CALLS + ("glTexStorage2D", "glGenerateMipmap")
# And those that give a texture read back from Mesa's replay of another
# target (rendered_textures.image_calls), which a reduced capture carries.
# A multisample texture read back: every sample of every layer, filled
# into Mesa's copy by vertex_textures.fill_samples (its arguments: target,
# samples, fixedsamplelocations, internalformat, width, height, depth =
# layers x samples, format, type, pixels).
SAMPLES_CALL = "rbcd-multisample-image"
READ_BACK_CALLS = ("glTexImage1D", "glTexImage3D", SAMPLES_CALL, "glTexStorage1D", "glTexStorage3D",
                   "glTexSubImage1D", "glTexSubImage3D")
SAMPLER_PARAMETER_CALLS = ("glSamplerParameteri", "glSamplerParameterf", "glSamplerParameteriv",
                           "glSamplerParameterfv", "glSamplerParameterIiv", "glSamplerParameterIuiv")


# Parameter values GL takes: a call that sets one replaces the earlier
# calls of its parameter; one GL may refuse is kept beside them, and Mesa
# decides.
FILTERS = {"GL_NEAREST", "GL_LINEAR"}
MIN_FILTERS = FILTERS | {f"GL_{a}_MIPMAP_{b}" for a in ("NEAREST", "LINEAR") for b in ("NEAREST", "LINEAR")}
WRAPS = {"GL_REPEAT", "GL_CLAMP_TO_EDGE", "GL_CLAMP_TO_BORDER", "GL_MIRRORED_REPEAT", "GL_MIRROR_CLAMP_TO_EDGE"}
COMPARE_FUNCS = {"GL_NEVER", "GL_LESS", "GL_EQUAL", "GL_LEQUAL", "GL_GREATER", "GL_NOTEQUAL", "GL_GEQUAL", "GL_ALWAYS"}
PARAMETER_VALUES = {"GL_TEXTURE_MIN_FILTER": MIN_FILTERS, "GL_TEXTURE_MAG_FILTER": FILTERS,
                    "GL_TEXTURE_WRAP_S": WRAPS, "GL_TEXTURE_WRAP_T": WRAPS, "GL_TEXTURE_WRAP_R": WRAPS,
                    "GL_TEXTURE_COMPARE_MODE": {"GL_NONE", "GL_COMPARE_REF_TO_TEXTURE"},
                    "GL_TEXTURE_COMPARE_FUNC": COMPARE_FUNCS}
# Formats, types and parameters of the compatibility profile alone: in a
# core profile's capture the call was GL_INVALID_ENUM or GL_INVALID_VALUE
# and changed nothing (Mesa's own context, of the compatibility profile,
# would take it).
COMPAT_TEXTURE_WORDS = ("LUMINANCE", "INTENSITY")
COMPAT_TEXTURE_PARAMETERS = {"GL_GENERATE_MIPMAP", "GL_DEPTH_TEXTURE_MODE", "GL_TEXTURE_PRIORITY"}


def compat_only(d):
    """Whether a texture or sampler call takes something a core profile
    does not have."""
    v = d.get("internalformat")   # (core Mesa takes luminance pixels: a format of the upload, not of the texture)
    if isinstance(v, str) and (any(w in v for w in COMPAT_TEXTURE_WORDS) or v.startswith("GL_ALPHA")) \
            or isinstance(v, int) and not isinstance(v, bool) and 1 <= v <= 4:   # the legacy component counts
        return True
    return d.get("pname") in COMPAT_TEXTURE_PARAMETERS or parameter_value(d) == "GL_CLAMP"


def parameter_certain(name, d):
    """Whether GL certainly takes a texture or sampler parameter call (a
    known parameter's value of the tables)."""
    v = parameter_value(d)
    return isinstance(v, (str, int, float)) and v in PARAMETER_VALUES.get(d.get("pname"), ())


def pixel_transfer_default(pname):
    """GL's initial value of a glPixelTransfer parameter: scales 1, the
    rest (biases, GL_MAP_COLOR, index shift and offset) 0."""
    return 1 if str(pname).endswith("_SCALE") else 0


class TextureCalls:
    """The calls that made one texture's images, in order (`calls`: sequence
    number -> (call number, name, arguments as a dict, pixel unpack state as
    a tuple)); `keyed`: the call a later one replaces, by what it sets (a
    part's rectangle, a parameter), so that a texture rewritten every frame
    costs one lookup a call; `version` changes with every call kept;
    `refused` is (call, reason) once the texture holds an image the
    converter cannot give Mesa; `over`: past the limits, nothing more is
    kept; `levels`: the levels whose image is known (level -> (internal
    format, width, height, type), texture_formats); `storage`: a
    glTexStorage2D kept (the texture may be immutable); `rendered`: (call,
    how) once the GPU renders its image (rendered_textures.py reads it back
    from Mesa's replay)."""
    __slots__ = ("calls", "keyed", "seq", "storage", "levels", "version", "bytes", "refused", "over", "rendered")

    def __init__(self):
        self.calls, self.keyed, self.seq, self.storage, self.levels = {}, {}, 0, False, {}
        self.version, self.bytes, self.refused, self.over, self.rendered = 0, 0, None, False, None


def pixel_bytes(no, what, d, unpack):
    """The bytes GL reads for an image call's pixels (glTex[Sub]Image{1,2,3}D
    and their direct state access forms: GL 4.5, 8.4.4.1) under the unpack
    state `unpack` (UNPACK_PARAMETERS' values), or None for a format or type
    not known here (`what` names the call in messages)."""
    w = checked(no, integer, d.get("width"), f"{what}: the width", *I32)
    h = checked(no, integer, d.get("height", 1), f"{what}: the height", *I32)
    depth = checked(no, integer, d.get("depth", 1), f"{what}: the depth", *I32)
    if w <= 0 or h <= 0 or depth <= 0:
        return 0
    fmt, kind = d.get("format"), d.get("type")
    if kind in PACKED_BYTES and fmt in FORMAT_COMPONENTS:
        elem, group = PACKED_BYTES[kind], PACKED_BYTES[kind]
    elif kind in TYPE_BYTES and fmt in FORMAT_COMPONENTS:
        elem, group = TYPE_BYTES[kind], TYPE_BYTES[kind] * FORMAT_COMPONENTS[fmt]
    else:
        return None
    state = dict(zip(UNPACK_PARAMETERS, unpack))
    row_length = state["GL_UNPACK_ROW_LENGTH"] or w
    align = state["GL_UNPACK_ALIGNMENT"]
    stride = row_length * group
    if elem < align:
        stride = -(-stride // align) * align
    image = (state["GL_UNPACK_IMAGE_HEIGHT"] or h) * stride   # (3D calls alone read the image parameters)
    skip_images = state["GL_UNPACK_SKIP_IMAGES"] if "depth" in d else 0
    return (skip_images + depth - 1) * image + state["GL_UNPACK_SKIP_ROWS"] * stride \
        + state["GL_UNPACK_SKIP_PIXELS"] * group + (h - 1) * stride + w * group


def pixels_of(d):
    p = d.get("pixels", d.get("data"))
    return p if isinstance(p, (bytes, bytearray)) else None


def replaced_by(name, d):
    """What a later call of the same key replaces: a part's rectangle, a
    parameter's value (None: nothing by key)."""
    if name in PART_CALLS:
        key = tuple(d.get(k) for k in ("level", "xoffset", "yoffset", "width", "height"))
        return ("part",) + key if all(isinstance(v, int) for v in key) else None
    if name in PARAMETER_CALLS:
        pname = d.get("pname")
        return ("parameter", pname) if isinstance(pname, (str, int)) else None
    return None


class TextureImageCalls:
    """self.s.texture_calls[texture] = TextureCalls of the 2D textures;
    self.s.unpack: the pixel unpack state; self.s.samplers[sampler] = {pname:
    [(name, arguments)]} (the calls that set it, in order), and
    self.s.sampler_units[unit] = sampler."""

    # ---- textures
    def bound_texture(self, target):
        return self.s.units.get((self.s.active_unit, target), 0)

    def texture_calls(self, tex):
        tc = self.s.texture_calls.get(tex)
        if tc is None:
            tc = self.s.texture_calls[tex] = TextureCalls()
        return tc

    def add_texture_call(self, tc, call):
        """Keeps a call after the texture's others, dropping those it
        certainly overwrites (texture_formats: only a call GL certainly
        takes replaces any)."""
        _, name, d, _ = call
        size = len(pixels_of(d)) if pixels_of(d) is not None else 0
        key = None
        if name in LEVEL_CALLS + PART_CALLS and d.get("target") != "GL_TEXTURE_2D":
            pass   # a cube map's face (read back): each face a level of its own, none replaced
        elif name in LEVEL_CALLS:
            level = certain_level(name, d, self.es) if not tc.storage else None
            if level is not None:
                lv = d["level"]   # a level defined again: its earlier image and parts go
                self.drop_texture_calls(tc, lambda c: c[1] in LEVEL_CALLS + PART_CALLS and c[2].get("level") == lv)
                tc.levels[lv] = level
            elif whole(d.get("level")):
                tc.levels.pop(d["level"], None)
        elif name in PART_CALLS:
            if certain_part(d, tc.levels.get(d.get("level")), self.es):
                key = replaced_by(name, d)
        elif name == "glTexStorage2D":
            levels = certain_storage(d) if not tc.storage else None
            if levels is not None:
                self.drop_texture_calls(tc, lambda c: c[1] in LEVEL_CALLS + PART_CALLS + ("glGenerateMipmap",))
            if not tc.storage:
                tc.levels = levels or {}
            tc.storage = True
        elif name == "glGenerateMipmap":
            if not any(c[1] in PARAMETER_CALLS and c[2].get("pname") in ("GL_TEXTURE_BASE_LEVEL", "GL_TEXTURE_MAX_LEVEL")
                       for c in tc.calls.values()) and certain_mipmaps(tc.levels, self.es):
                # Every level past 0 made again: an earlier regeneration
                # of them is overwritten.
                self.drop_texture_calls(tc, lambda c: c[1] == "glGenerateMipmap")
            if not tc.storage:   # the levels past the base one change (the base may be past 0)
                tc.levels = {k: v for k, v in tc.levels.items() if k == 0}
        elif parameter_certain(name, d):
            key = replaced_by(name, d)
        if key is not None and key in tc.keyed:
            self.drop_texture_call(tc, tc.keyed[key])
        tc.seq += 1
        tc.calls[tc.seq] = call
        if key is not None:
            tc.keyed[key] = tc.seq
        tc.bytes += size
        self.s.texture_bytes_kept += size
        self.s.next_version += 1
        tc.version = self.s.next_version

    def drop_texture_call(self, tc, seq):
        _, name, d, _ = tc.calls.pop(seq)
        key = replaced_by(name, d)
        if key is not None and tc.keyed.get(key) == seq:
            del tc.keyed[key]
        if pixels_of(d) is not None:
            tc.bytes -= len(pixels_of(d))
            self.s.texture_bytes_kept -= len(pixels_of(d))

    def drop_texture_calls(self, tc, drop):
        """Drops the calls for which drop(call) holds (a scan: for the calls
        that redefine a level or the whole texture, made once or rarely)."""
        for seq in [k for k, c in tc.calls.items() if drop(c)]:
            self.drop_texture_call(tc, seq)

    def unpack_state(self):
        """The pixel unpack state, UNPACK_PARAMETERS' values."""
        return tuple(self.s.unpack.get(p, UNPACK_DEFAULTS.get(p, 0)) for p in UNPACK_PARAMETERS)

    def pixels_held(self, no, name, d):
        """An image call's pixels in the capture hold what GL reads for its
        size, format, type and unpack state (a compressed one's: imageSize);
        apitrace records at least that much, so fewer is the capture's error,
        named: a capture cut or altered, or apitrace 11.1's empty record of
        pixels of GL_HALF_FLOAT_OES. The image is not in the capture: its
        digest (selection rules' texture_image) would be another image's,
        and Mesa would read past it (vertex textures, the depth check's
        replay). An offset into a pixel unpack buffer, NULL, or a reduced
        capture's digest is not checked here."""
        pixels = pixels_of(d)
        if pixels is None or self.s.bound.get("GL_PIXEL_UNPACK_BUFFER", 0):
            return
        what = printable(name)
        if base_name(name).startswith("glCompressed"):
            need = max(d.get("imageSize", 0), 0)   # (checked a GLsizei; a negative one is GL_INVALID_VALUE)
        else:
            need = pixel_bytes(no, what, d, self.unpack_state())
        if need is not None and len(pixels) < need:
            why = "apitrace 11.1 records none of type GL_HALF_FLOAT_OES" if d.get("type") == "GL_HALF_FLOAT_OES" \
                else "the capture is cut or altered"
            fail_call(no, f"{what}: {len(pixels)} bytes of pixels, {need} read by GL for its size, format and "
                      f"unpack state ({why})")

    def keep_texture_call(self, no, name, d):
        """An image or parameter call on the bound 2D texture, kept (the
        pixels too) with the calls it does not replace."""
        if d.get("target") != VERTEX_TEXTURE_TARGET:
            self.gpu_wrote()   # a texture of another target changed: read back again (rendered_textures)
            return
        tex = self.bound_texture(VERTEX_TEXTURE_TARGET)
        if self.core and compat_only(d):
            return   # GL_INVALID_ENUM or GL_INVALID_VALUE in the capture's core profile: nothing changes
        if tex in self.s.views:
            # A texture that shares its images with a view (or is one): the
            # others are read back again too.
            self.gpu_wrote()
        tc = self.texture_calls(tex)
        if tc.over:
            return
        if name in LEVEL_CALLS and refused_level(name, d) or name in PART_CALLS and \
                refused_part(name, d, tc.levels.get(d.get("level"))) or \
                name == "glTexStorage2D" and refused_storage(d):
            return   # GL certainly refuses it: it changes nothing, and is not kept (memory and time)
        pixels = d.get("pixels", d.get("data"))
        if name in LEVEL_CALLS + PART_CALLS:
            unpack_buffer = self.s.bound.get("GL_PIXEL_UNPACK_BUFFER", 0)
            transfer = sorted(str(k) for k, v in self.s.pixel_transfer.items() if v != pixel_transfer_default(k))
            if transfer:
                tc.refused = (no, f"{name} converted its pixels under pixel transfer state ({', '.join(transfer)}), "
                                  "which is not emulated")
            elif unpack_buffer:
                tc.refused = (no, f"{name} read its pixels from pixel unpack buffer {unpack_buffer}")
            elif isinstance(pixels, int) and not isinstance(pixels, bool) and pixels:
                tc.refused = (no, f"{name}'s pixels are not in the capture (a pointer apitrace did not follow)")
        elif name == "glGenerateMipmap" and tc.calls and next(reversed(tc.calls.values()))[1] == name:
            return
        data = pixels_of(d)
        size = len(data) if data is not None else 0
        if self.s.texture_bytes_kept + size > MAX_TEXTURE_BYTES_KEPT or len(tc.calls) >= MAX_TEXTURE_CALLS_KEPT:
            self.drop_texture_calls(tc, lambda c: True)
            tc.over = True
            tc.refused = (no, f"more than {MAX_TEXTURE_BYTES_KEPT >> 20} MiB of texture images, or "
                              f"{MAX_TEXTURE_CALLS_KEPT} calls for one texture, would be kept")
            return
        self.add_texture_call(tc, (no, name, d, self.unpack_state()))

    def texture_rendered(self, tex, no, how):
        """A texture whose image the GPU writes: a vertex shader that reads
        it gets it read back from Mesa's replay (rendered_textures.py)."""
        self.gpu_wrote()
        if self.s.texture_targets.get(tex, VERTEX_TEXTURE_TARGET) == VERTEX_TEXTURE_TARGET:
            self.texture_calls(tex).rendered = (no, how)

    def gpu_wrote(self):
        """The GPU may have written a texture (a draw, clear or copy into a
        framebuffer object, an attachment): rendered textures are read back
        again at the next draw that reads them."""
        self.s.gpu_writes += 1

    def rendered_textures(self, no, name, reads):
        """The textures of `reads` [(unit, texture, TextureCalls or None,
        target)] that Mesa's replay gives: 2D ones the GPU renders or whose
        calls the converter cannot give Mesa, and every texture of another
        target (the converter keeps no calls for those). Each as
        TextureCalls that make the image and sampling parameters the replay
        has at call `no` (rendered_textures.py): {(texture, target):
        TextureCalls}, read again only when the GPU or a texture call may
        have changed them since (the draws of one multi-draw share what was
        read at their call: the replay passes each call once)."""
        out, ask = {}, []
        read_at = self.s.readback_call   # (call, the textures read back there)
        for unit, tex, tc, target in reads:
            version = ("read back", self.s.gpu_writes, tc.version if tc is not None else 0)
            cached = self.s.rendered_images.get((tex, target))
            if cached is not None and (cached.version == version or read_at is not None and read_at[0] == no
                                       and (tex, target) in read_at[1]):
                out[(tex, target)] = cached
            else:
                ask.append((unit, tex, tc, target, version))
        if not ask:
            return out
        unit, tex, tc, target, _ = ask[0]
        tex = tex if tex < DEFAULT_TEXTURE_BASE else 0
        unit = f"unit {unit}" if unit < IMAGE_UNIT_BASE else f"image unit {unit - IMAGE_UNIT_BASE}"
        if tc is None:
            what = f"texture {tex} ({target}, {unit})"
        elif tc.refused is not None:
            what = f"texture {tex} ({unit}), whose image the converter cannot give Mesa (call " \
                   f"{tc.refused[0]}: {printable(tc.refused[1])})"
        else:
            what = f"texture {tex} ({unit}), which the GPU renders (call {tc.rendered[0]}: " \
                   f"{printable(tc.rendered[1])})"
        if self.reads_reduced:
            fail_call(no, f"{name}: its vertex shader reads {what}: a reduced capture carries only the images a "
                      "conversion of the capture read back (with the draws that read them)")
        if read_at is not None and read_at[0] == no:
            fail_call(no, f"{name}: its vertex shader reads {what}, which Mesa's replay was not asked for at the "
                      "call's first draw (a multi-draw whose draws read other textures): not emulated")
        from ..rendered_textures import RenderedTextures, image_calls
        if self.replay is None:
            try:
                self.replay = RenderedTextures(self.args.trace, getattr(self.args, "check_timeout", 600))
            except ToolError as e:   # a tool missing: said with the draw that needs it
                raise ToolError(f"call {no}: {printable(name)}: its vertex shader reads {what}: {e}")
        images = self.replay.read(no, name, [(unit, target) for unit, _, _, target, _ in ask])
        self.s.readback_call = (no, {(tex, target) for _, tex, _, target, _ in ask})
        unpack = tuple(1 if p == "GL_UNPACK_ALIGNMENT" else 0 for p in UNPACK_PARAMETERS)
        for unit, tex, tc, target, version in ask:
            internal, params, levels = images.get((unit, target), (0, [], []))
            rt = TextureCalls()
            if target in MULTISAMPLE_TARGETS:
                # Its samples as read (without its swizzle: a depth
                # format's first component is the depth), the swizzle
                # given again (the other parameters do not apply to a
                # multisample texture).
                samples = next((v for p, v in params if p == GL_TEXTURE_SAMPLES), None)
                calls = [(no, SAMPLES_CALL, dict(target=target, samples=int(samples[0]),
                                                 fixedsamplelocations=int(samples[1]), internalformat=internal,
                                                 width=w, height=h, depth=depth, format=fmt, type=kind,
                                                 pixels=pixels))
                         for level, w, h, depth, fmt, kind, pixels in levels if samples and level == 0]
                params = [(p, v) for p, v in params if p in SWIZZLE_PARAMETERS]
            else:
                immutable = next((int(v[0]) for p, v in params if p == GL_TEXTURE_IMMUTABLE_LEVELS), 0)
                params = [(p, v) for p, v in params if p != GL_TEXTURE_IMMUTABLE_LEVELS]
                calls = image_calls(no, target, internal, levels, self.es, immutable)
            for call in calls:
                rt.seq += 1
                rt.calls[rt.seq] = call + (unpack,)
            for pname, values in params:
                rt.seq += 1
                rt.calls[rt.seq] = (no, "glTexParameterfv", dict(target=target, pname=pname, params=values), unpack)
            rt.version = version
            self.s.rendered_images[(tex, target)] = out[(tex, target)] = rt
        return out

    def close_replay(self):
        if self.replay is not None:
            self.replay.close()
            self.replay = None

    def forget_texture_calls(self, tex):
        for key in [k for k in self.s.rendered_images if k[0] == tex]:
            del self.s.rendered_images[key]
        tc = self.s.texture_calls.pop(tex, None)
        if tc is not None:
            self.s.texture_bytes_kept -= tc.bytes

    def h_pixel_store(self, no, name, a, args):
        d = dict(args)
        pname = d.get("pname")
        if pname in UNPACK_PARAMETERS:
            value = d.get("param")
            if isinstance(value, float) and math.isfinite(value):
                # glPixelStoref rounds to the nearest integer, halves away
                # from zero (Mesa's IROUND).
                value = int(math.floor(abs(value) + 0.5)) * (1 if value >= 0 else -1)
            value = checked(no, integer, value, f"{name}: {pname}", *I32)
            # Mesa's GL_INVALID_VALUE (negative, or an alignment other than
            # 1, 2, 4, 8) leaves the state as it was.
            if value < 0 or pname == "GL_UNPACK_ALIGNMENT" and value not in (1, 2, 4, 8):
                return
            self.s.unpack[pname] = value

    def h_pixel_transfer(self, no, name, a, args):
        """glPixelTransferf/i (compatibility profile): scales, biases and
        colour maps GL applies to the pixels of a glTexImage2D; a texture
        made under any but the default is refused if a vertex shader reads
        it."""
        d = dict(args)
        pname, value = d.get("pname"), d.get("param")
        if isinstance(pname, str) and isinstance(value, (int, float)) and not isinstance(value, bool):
            self.s.pixel_transfer[pname] = value

    def texture_view(self, no, name, a, args):
        """glTextureView: the view and the texture it views share images.
        Where GL certainly makes the view, its images are the original's
        levels and layers it names (texture_levels.record_view: its size
        and completeness as attached); where it certainly refuses, nothing
        changes; otherwise neither texture's images are known. Either way
        the pixels the two share are not followed: both are read back
        from Mesa's replay when a vertex shader reads them, again after
        any texture call on either (keep_texture_call)."""
        d = dict(args)
        view, orig = d.get("texture"), d.get("origtexture")
        made = self.record_view(d)
        if made == "refused":
            return
        for tex in (view, orig):
            if isinstance(tex, int) and not isinstance(tex, bool) and tex > 0:
                self.s.views.add(tex)
                if made is None:
                    self.levels_unfollowed(tex, f"a view (call {no}, {name})")
                if tex == view and isinstance(d.get("target"), str):
                    self.s.texture_targets.setdefault(tex, d["target"])
                self.texture_calls(tex).refused = (no, f"{name} makes texture {view} a view of texture {orig}, "
                                                       "which is not emulated")

    def h_keep(self, no, name, a, args):
        """glTexParameter*, glGenerateMipmap: kept with the bound 2D
        texture's calls, and the levels they make or choose
        (texture_levels)."""
        d = dict(args)
        if base_name(name) == "glGenerateMipmap":
            self.record_mipmaps(no, name, d)
        else:
            self.level_range_set(d)
        self.keep_texture_call(no, base_name(name), d)

    def h_copy_tex_image(self, no, name, a, args):
        """glCopyTexImage2D, glCopyTexSubImage2D: the GPU writes the bound 2D
        texture (a vertex shader that reads it gets it from Mesa's replay);
        as a camera-pass depth buffer its contents are not followed; and
        glCopyTexImage2D gives the level its size and format, as
        glTexImage2D does (a framebuffer it is attached to may become the
        camera pass), unless GL certainly refuses it."""
        d = dict(args)
        if base_name(name) == "glCopyTexImage2D" and self.record_levels(no, base_name(name), d) \
                and d.get("target") != VERTEX_TEXTURE_TARGET:
            self.texture_levels_changed(d)
        if d.get("target") != VERTEX_TEXTURE_TARGET:
            self.gpu_wrote()   # a cube map's face: read back again (texture_rendered says so of a 2D texture)
            return
        tex = self.bound_texture(VERTEX_TEXTURE_TARGET)
        self.texture_rendered(tex, no, f"{name} copies the framebuffer into it")
        level = d.get("level", 0)
        if not (whole(level) and 0 <= level <= MAX_LEVEL):
            return   # GL_INVALID_VALUE
        if tex in self.s.texture_calls:
            self.s.texture_calls[tex].levels.pop(level, None)   # its size and format are the copy's now
        key = ("texture", tex) if level == 0 else ("texture", tex, level)
        if base_name(name) == "glCopyTexImage2D":
            if not (level_size_fits(d) and d.get("border") == 0 and isinstance(d.get("internalformat"), str)):
                return   # GL_INVALID_VALUE or GL_INVALID_ENUM: nothing changes
            if (self.s.sizes.get(key), self.s.formats.get(key)) != ((d["width"], d["height"]), d["internalformat"]):
                # (the level as it was: Mesa copies into it, which gives no
                # new image to framebuffers it is attached to)
                self.texture_levels_changed(d)
            self.s.sizes[key] = (d["width"], d["height"])
            self.s.formats[key] = d["internalformat"]
        self.depths_replaced(key, f"were written by call {no} ({printable(name)}: a copy of the read framebuffer, "
                                  "which the converter does not follow)")

    def vertex_texture_read(self, tex, tc):
        """A draw's vertex shader reads texture `tex`: for --reduced-out,
        the calls that made it go with the draw, unless these very calls
        went with an earlier draw."""
        if not self.writes_reduced or tc is None or self.s.reduced_texture_versions.get(tex) == tc.version:
            return
        from ..reduced import plain_value
        self.s.reduced_texture_versions[tex] = tc.version
        self.reduced_textures.append((tex, [(no, name, [(k, plain_value(v)) for k, v in d.items()], list(unpack))
                                            for no, name, d, unpack in tc.calls.values()]))

    def take_reduced_textures(self):
        taken, self.reduced_textures = self.reduced_textures, []
        return taken

    def restore_texture_calls(self, no, name, value):
        """A reduced capture's REDUCED_TEXTURES: each texture's calls as
        the converter that wrote it kept them, in place of its own (whose
        images the reduced capture left out)."""
        what = f"{printable(name)}: its {REDUCED_TEXTURES} (the reduced capture's)"
        if not isinstance(value, list):
            fail_call(no, f"{what}: not a list")
        for item in value:
            if not (isinstance(item, tuple) and len(item) == 2 and isinstance(item[1], list)
                    and len(item[1]) <= MAX_TEXTURE_CALLS_KEPT):
                fail_call(no, f"{what}: a texture's record that is not (texture, calls)")
            tex = checked(no, integer, item[0], f"{what}: a texture", 0, DEFAULT_TEXTURE_BASE + 0xFFFF)
            if U32[1] < tex < DEFAULT_TEXTURE_BASE:
                fail_call(no, f"{what}: a texture name past 32 bits that names no target's default texture")
            self.forget_texture_calls(tex)
            tc = self.texture_calls(tex)
            for c in item[1]:
                if not (isinstance(c, tuple) and len(c) == 4 and c[1] in KEPT_CALLS + READ_BACK_CALLS
                        and isinstance(c[2], list)
                        and all(isinstance(x, tuple) and len(x) == 2 and isinstance(x[0], str) for x in c[2])
                        and isinstance(c[3], list) and len(c[3]) == len(UNPACK_PARAMETERS)):
                    fail_call(no, f"{what}: a call's record that is not (call, name, arguments, unpack state)")
                call_no = checked(no, integer, c[0], f"{what}: a call number", *U63)
                unpack = tuple(checked(no, integer, v, f"{what}: an unpack parameter", *I32) for v in c[3])
                if min(unpack) < 0 or unpack[UNPACK_PARAMETERS.index("GL_UNPACK_ALIGNMENT")] not in (1, 2, 4, 8):
                    fail_call(no, f"{what}: an unpack state GL cannot hold")   # Mesa would read other bytes
                d = dict(c[2])
                size = len(pixels_of(d)) if pixels_of(d) is not None else 0
                if self.s.texture_bytes_kept + size > MAX_TEXTURE_BYTES_KEPT:
                    fail_call(no, f"{what}: more than {MAX_TEXTURE_BYTES_KEPT >> 20} MiB of texture images")
                self.add_texture_call(tc, (call_no, c[1], d, unpack))

    # ---- image units
    def h_bind_image_texture(self, no, name, a, args):
        """glBindImageTexture (GL 4.2, ES 3.1) and glBindImageTextures (GL
        4.4: level 0, every layer, read and write, the texture's own
        format): what a vertex shader's image uniforms read. What GL
        refuses binds nothing (a unit past llvmpipe's 192, no such texture,
        a negative level or layer, an access or format GL does not take). A
        texture bound for writing is one the GPU may render: read back from
        Mesa's replay when a vertex shader reads it, again after each draw
        while it is bound so."""
        d = dict(args)
        if base_name(name) == "glBindImageTexture":
            unit = checked(no, integer, d.get("unit"), f"{name}: the unit", *U32)
            tex = checked(no, integer, d.get("texture"), f"{name}: the texture", *U32)
            level = checked(no, integer, d.get("level"), f"{name}: the level", *I32)
            layer = checked(no, integer, d.get("layer"), f"{name}: the layer", *I32)
            layered = gl_boolean(d.get("layered"), no, f"{name}: layered", nonzero=True)
            access, fmt = d.get("access"), d.get("format")
            if unit >= MAX_IMAGE_UNITS or level < 0 or layer < 0 or access not in IMAGE_ACCESS \
                    or fmt not in IMAGE_FORMATS or tex and tex not in self.s.texture_targets:
                return   # GL_INVALID_VALUE or GL_INVALID_ENUM: the unit keeps its binding
            binds = [(unit, tex, (tex, level, layered, layer, access, fmt))]
        else:
            first = checked(no, integer, d.get("first"), f"{name}: first", *U32)
            count = checked(no, integer, d.get("count"), f"{name}: count", *I32)
            texs = d.get("textures")
            if count < 0 or first + count > MAX_IMAGE_UNITS:
                return   # GL_INVALID_VALUE or _OPERATION: nothing is bound
            if texs is None or texs == 0 and not isinstance(texs, bool):   # NULL: every unit unbound
                texs = [0] * count
            if not isinstance(texs, list) or len(texs) < count:
                fail_call(no, f"{name}: fewer textures than its count")
            binds = []
            for i, tex in enumerate(texs[:count]):
                tex = checked(no, integer, tex, f"{name}: a texture", *U32)
                fmt = self.s.formats.get(("texture", tex))
                if tex and (tex not in self.s.texture_targets or fmt is not None and fmt not in IMAGE_FORMATS):
                    continue   # no such texture or no image format: GL_INVALID_OPERATION, the unit is skipped
                layered = self.s.texture_targets.get(tex) not in ("GL_TEXTURE_1D", "GL_TEXTURE_2D",
                                                                  "GL_TEXTURE_RECTANGLE", "GL_TEXTURE_BUFFER")
                binds.append((first + i, tex, (tex, 0, layered, 0, "GL_READ_WRITE", fmt)))   # (None: Mesa's)
        for unit, tex, binding in binds:
            if not tex:
                self.s.image_units.pop(unit, None)
                self.s.image_writes.discard(unit)
                continue
            self.s.image_units[unit] = binding
            if binding[4] == "GL_READ_ONLY":
                self.s.image_writes.discard(unit)
            else:
                self.s.image_writes.add(unit)
                self.texture_rendered(tex, no, f"{name} binds it to image unit {unit} for writing")

    # ---- sampler objects
    def h_bind_sampler(self, no, name, a, args):
        d = dict(args)
        if name == "glBindSampler":
            pairs = [(d.get("unit"), d.get("sampler"))]
        else:
            first = checked(no, integer, d.get("first"), f"{name}: first", *U32)
            count = checked(no, integer, d.get("count"), f"{name}: count", *I32)
            samplers = d.get("samplers")
            if samplers is None or samplers == 0 and not isinstance(samplers, bool):   # NULL, recorded as 0
                samplers = [0] * max(count, 0)
            if not isinstance(samplers, list) or len(samplers) < count:
                fail_call(no, f"{name}: fewer samplers than its count")
            pairs = [(first + i, s) for i, s in enumerate(samplers[:max(count, 0)])]
            if first + max(count, 0) > MAX_TEXTURE_UNITS:
                return   # GL_INVALID_OPERATION: nothing is bound
        for unit, sampler in pairs:
            unit = checked(no, integer, unit, f"{name}: the unit", *U32)
            sampler = checked(no, integer, sampler, f"{name}: the sampler", *U32)
            if sampler and self.s.sampler_names is not None and sampler not in self.s.sampler_names:
                continue   # no such sampler: GL_INVALID_OPERATION, the unit keeps its binding
            self.s.sampler_units[unit] = sampler

    def h_sampler_parameter(self, no, name, a, args):
        d = dict(args)
        sampler = checked(no, integer, d.get("sampler"), f"{name}: the sampler", *U32)
        if not isinstance(d.get("pname"), (str, int)) or isinstance(d.get("pname"), bool):
            fail_call(no, f"{name}: a parameter name that is no enumerant")
        if self.core and compat_only(d):
            return   # not in the capture's core profile: the call changed nothing
        # A call GL may refuse is kept beside the earlier ones of its
        # parameter (Mesa decides), one it takes replaces them.
        params = self.s.samplers.setdefault(sampler, {})
        kept = params.pop(d["pname"], [])
        params[d["pname"]] = ([] if parameter_certain(base_name(name), d) else kept[-15:]) + [(base_name(name), d)]

    def h_delete_samplers(self, no, name, a, args):
        for sampler in dict(args).get("samplers") or []:
            if isinstance(sampler, int) and not isinstance(sampler, bool) and sampler > 0:
                if self.s.sampler_names is not None:
                    self.s.sampler_names.discard(sampler)
                self.s.samplers.pop(sampler, None)
                for unit, bound in list(self.s.sampler_units.items()):
                    if bound == sampler:
                        self.s.sampler_units[unit] = 0

    def h_tex_env(self, no, name, a, args):
        """glTexEnv: of its parameters only the texture unit's level-of-detail
        bias (GL_TEXTURE_FILTER_CONTROL, GL_TEXTURE_LOD_BIAS, a
        compatibility profile's) changes what a vertex shader's texture()
        reads: kept per unit, given to Mesa's context at the draw (round
        16's R16-2: level 0 read where Mesa read level 1). The others are
        fixed-function shading, nil on the unit's input."""
        d = dict(args)
        if d.get("target") != "GL_TEXTURE_FILTER_CONTROL" or d.get("pname") != "GL_TEXTURE_LOD_BIAS":
            return
        value = parameter_value(d)
        if base_name(name).endswith(("x", "xv")):
            value = number(value, no, f"{printable(name)}: the bias") / 65536.0
        bias = number(value, no, f"{printable(name)}: the bias")
        if bias:
            self.s.unit_lod_bias[self.s.active_unit] = bias
        else:
            self.s.unit_lod_bias.pop(self.s.active_unit, None)

    HANDLERS = {
        "glTexEnvf": h_tex_env,
        "glTexEnvi": h_tex_env,
        "glTexEnvfv": h_tex_env,
        "glTexEnviv": h_tex_env,
        "glTexEnvx": h_tex_env,
        "glTexEnvxv": h_tex_env,
        "glPixelStorei": h_pixel_store,
        "glPixelTransferf": h_pixel_transfer,
        "glPixelTransferi": h_pixel_transfer,
        "glTextureView": texture_view,
        "glPixelStoref": h_pixel_store,
        "glGenerateMipmap": h_keep,
        "glCopyTexImage2D": h_copy_tex_image,
        "glCopyTexSubImage2D": h_copy_tex_image,
        "glBindImageTexture": h_bind_image_texture,
        "glBindImageTextures": h_bind_image_texture,
        "glBindSampler": h_bind_sampler,
        "glBindSamplers": h_bind_sampler,
        "glDeleteSamplers": h_delete_samplers,
        "glGenTextures": FramebufferCalls.h_gen_names,
        "glGenSamplers": FramebufferCalls.h_gen_names,
        "glCreateSamplers": FramebufferCalls.h_gen_names,
    } | dict.fromkeys(PARAMETER_CALLS, h_keep) \
      | dict.fromkeys(SAMPLER_PARAMETER_CALLS, h_sampler_parameter)

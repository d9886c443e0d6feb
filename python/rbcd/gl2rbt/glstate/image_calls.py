"""The arguments of texture image, attachment and view calls, checked as the
project's input rule asks before any handler reads them (converter.handle):
whole numbers of the C types' widths, enumerants as apitrace writes them,
pixels as bytes, an offset or a reduced capture's digest, and the sizes,
offsets, levels, samples and layers every call of its kind has. Anything
else is the capture's error, in one line naming the call. Texture targets,
cube map faces and framebuffer attachment points given by value (apitrace
writes names) are taken as the enumerant of that value, as the driver
takes them."""
import re

from ...cli import I32, U32, integer
from ..errors import checked, fail_call, printable
from . import enum_arg, gl_boolean
from .texture_formats import is_digest
from .texture_levels import CUBE_FACES

# Texture image calls by their base name: (Compressed|Copy)?, the direct
# state access form or not, Sub or not, Image or Storage, the dimensions,
# Multisample; and the calls that attach or view a texture's images.
IMAGE_CALL = re.compile(r"gl(Compressed|Copy)?(Tex|Texture)(Sub)?(Image|Storage)([123])D(Multisample)?")
ATTACHING_CALL = re.compile(r"gl(Named)?Framebuffer(Texture|Renderbuffer)(Layer|[123]D)?|glTextureView"
                            r"|gl(Named)?RenderbufferStorage(Multisample)?|glBind(Texture|Framebuffer|Renderbuffer)")
# The arguments of each call of ATTACHING_CALL, in apitrace's names.
ATTACHING_ARGS = {
    "glFramebufferTexture": ("target", "attachment", "texture", "level"),
    "glFramebufferTexture1D": ("target", "attachment", "textarget", "texture", "level"),
    "glFramebufferTexture2D": ("target", "attachment", "textarget", "texture", "level"),
    "glFramebufferTexture3D": ("target", "attachment", "textarget", "texture", "level", "zoffset"),
    "glFramebufferTextureLayer": ("target", "attachment", "texture", "level", "layer"),
    "glNamedFramebufferTexture": ("framebuffer", "attachment", "texture", "level"),
    "glNamedFramebufferTextureLayer": ("framebuffer", "attachment", "texture", "level", "layer"),
    "glFramebufferRenderbuffer": ("target", "attachment", "renderbuffertarget", "renderbuffer"),
    "glNamedFramebufferRenderbuffer": ("framebuffer", "attachment", "renderbuffertarget", "renderbuffer"),
    "glTextureView": ("texture", "target", "origtexture", "internalformat", "minlevel", "numlevels", "minlayer",
                      "numlayers"),
    "glRenderbufferStorage": ("target", "internalformat", "width", "height"),
    "glRenderbufferStorageMultisample": ("target", "samples", "internalformat", "width", "height"),
    "glNamedRenderbufferStorage": ("renderbuffer", "internalformat", "width", "height"),
    "glNamedRenderbufferStorageMultisample": ("renderbuffer", "samples", "internalformat", "width", "height"),
    "glBindTexture": ("target", "texture"),
    "glBindFramebuffer": ("target", "framebuffer"),
    "glBindRenderbuffer": ("target", "renderbuffer"),
}
# Their arguments by kind: GLint and GLsizei values; object names and
# glTextureView's levels and layers (GLuint); enumerants (a GLint internal
# format may be a number, as the legacy component counts are).
INT_ARGS = {"level", "levels", "width", "height", "depth", "border", "xoffset", "yoffset", "zoffset", "x", "y",
            "samples", "imageSize", "layer"}
NAME_ARGS = {"texture", "origtexture", "framebuffer", "renderbuffer", "minlevel", "numlevels", "minlayer", "numlayers"}
BOOLEAN_ARGS = {"fixedsamplelocations"}
ENUM_ARGS = {"target", "format", "type", "attachment", "textarget", "renderbuffertarget", "internalformat"}
PIXEL_ARGS = {"pixels", "data"}
# Texture targets, cube map faces, framebuffer targets and attachment points
# by value.
ENUM_VALUES = {
    0x0DE0: "GL_TEXTURE_1D", 0x0DE1: "GL_TEXTURE_2D", 0x806F: "GL_TEXTURE_3D", 0x8C18: "GL_TEXTURE_1D_ARRAY",
    0x8C1A: "GL_TEXTURE_2D_ARRAY", 0x84F5: "GL_TEXTURE_RECTANGLE", 0x8513: "GL_TEXTURE_CUBE_MAP",
    0x9009: "GL_TEXTURE_CUBE_MAP_ARRAY", 0x8C2A: "GL_TEXTURE_BUFFER", 0x9100: "GL_TEXTURE_2D_MULTISAMPLE",
    0x9102: "GL_TEXTURE_2D_MULTISAMPLE_ARRAY", 0x8D65: "GL_TEXTURE_EXTERNAL_OES",
    **{0x8515 + i: face for i, face in enumerate(CUBE_FACES)},
    0x8D40: "GL_FRAMEBUFFER", 0x8CA9: "GL_DRAW_FRAMEBUFFER", 0x8CA8: "GL_READ_FRAMEBUFFER",
    0x8D00: "GL_DEPTH_ATTACHMENT", 0x8D20: "GL_STENCIL_ATTACHMENT", 0x821A: "GL_DEPTH_STENCIL_ATTACHMENT",
    0x8D41: "GL_RENDERBUFFER", **{0x8CE0 + i: f"GL_COLOR_ATTACHMENT{i}" for i in range(32)}}
TEXTURE_TARGETS = frozenset(v for v in ENUM_VALUES.values() if v.startswith("GL_TEXTURE") and v not in CUBE_FACES)
NAMED_VALUE_ARGS = {"target", "textarget", "attachment", "renderbuffertarget"}


def by_value(v):
    """An enumerant of ENUM_VALUES given by its value, by name; any other
    value as it is."""
    return ENUM_VALUES.get(v, v) if isinstance(v, int) and not isinstance(v, bool) else v


def checked_calls(names):
    """The base names among `names` (the handled calls) whose arguments
    image_call_args checks."""
    return frozenset(n for n in names if IMAGE_CALL.fullmatch(n) or ATTACHING_CALL.fullmatch(n))


def call_args(name):
    """The arguments apitrace writes for a call of ATTACHING_CALL or
    IMAGE_CALL (by its name: an EXT_direct_state_access form names the
    texture and its target): each once, none other."""
    base = name[:-3] if name.endswith("EXT") else name
    if base in ATTACHING_ARGS:
        return ATTACHING_ARGS[base]
    m = IMAGE_CALL.fullmatch(base)
    if m is None:
        return None
    compressed, copy = m.group(1) == "Compressed", m.group(1) == "Copy"
    dsa, sub, storage, dims, multisample = m.group(2) == "Texture", m.group(3), m.group(4) == "Storage", \
        int(m.group(5)), m.group(6)
    names = ["texture"] if dsa else []
    if not dsa or name.endswith("EXT"):
        names.append("target")
    sizes = ["width", "height", "depth"][:min(dims, 2) if copy else dims]
    offsets = ["xoffset", "yoffset", "zoffset"][:dims] if sub else []
    if multisample:
        return tuple(names + ["samples", "internalformat"] + sizes + ["fixedsamplelocations"])
    if storage:
        return tuple(names + ["levels", "internalformat"] + sizes)
    names.append("level")
    if copy:
        return tuple(names + (offsets + ["x", "y"] if sub else ["internalformat", "x", "y"]) + sizes
                     + ([] if sub else ["border"]))
    if sub:
        return tuple(names + offsets + sizes + ["format"] + (["imageSize", "data"] if compressed else
                                                             ["type", "pixels"]))
    return tuple(names + ["internalformat"] + sizes + ["border"] + (["imageSize", "data"] if compressed else
                                                                    ["format", "type", "pixels"]))


def image_call_args(no, raw, args):
    """The call's arguments checked (the module's rule), targets and
    attachment points by value named."""
    name = printable(raw)
    out = []
    for k, v in args:
        if k in INT_ARGS:
            checked(no, integer, v, f"{name}: the {k}", *I32)
        elif k in NAME_ARGS:
            checked(no, integer, v, f"{name}: the {k}", *U32)
        elif k in ENUM_ARGS:
            if k == "internalformat" and isinstance(v, int) and not isinstance(v, bool) and -(1 << 31) <= v < 0:
                pass   # (a GLint: GL_INVALID_VALUE)
            else:
                v = enum_arg(v, no, f"{name}: the {k}")
            if k in NAMED_VALUE_ARGS:
                v = by_value(v)
        elif k in BOOLEAN_ARGS:
            gl_boolean(v, no, f"{name}: the {k}")
        elif k in PIXEL_ARGS:
            if isinstance(v, tuple):
                if not is_digest(v):
                    fail_call(no, f"{name}: the {k}: {printable(v, 40)} is neither an image nor its digest")
            elif not (v is None or isinstance(v, (bytes, bytearray))):
                checked(no, integer, v, f"{name}: the {k} (an offset)", 0, (1 << 64) - 1)
        out.append((k, v))
    want = call_args(raw)
    keys = [k for k, _ in args]
    if want is not None and (len(keys) != len(want) or set(keys) != set(want)):
        missing = [k for k in want if k not in keys]
        extra = sorted({printable(k, 40) for k in keys if k not in want}) or ["one twice"]
        fail_call(no, f"{name}: " + (f"no {missing[0]}" if missing else f"arguments apitrace does not write "
                                     f"({', '.join(extra)})") + f" (it writes {', '.join(want)})")
    return out

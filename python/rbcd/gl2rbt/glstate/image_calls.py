"""The arguments of texture image, attachment and view calls, checked as the
project's input rule asks before any handler reads them (converter.handle):
whole numbers of the C types' widths, enumerants as apitrace writes them,
pixels as bytes, an offset or a reduced capture's digest, and the sizes,
offsets, levels, samples and layers every call of its kind has. Anything
else is the capture's error, in one line naming the call. (Enumerants
given by value are named before: gl_registry.named_enumerants.)"""
import re

from ...cli import I32, U32, integer
from ..errors import checked, fail_call, printable
from . import enum_arg, gl_boolean
from .texture_formats import is_digest

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
# The targets glBindTexture and the direct state access calls take.
TEXTURE_TARGETS = frozenset({
    "GL_TEXTURE_1D", "GL_TEXTURE_2D", "GL_TEXTURE_3D", "GL_TEXTURE_1D_ARRAY", "GL_TEXTURE_2D_ARRAY",
    "GL_TEXTURE_RECTANGLE", "GL_TEXTURE_CUBE_MAP", "GL_TEXTURE_CUBE_MAP_ARRAY", "GL_TEXTURE_BUFFER",
    "GL_TEXTURE_2D_MULTISAMPLE", "GL_TEXTURE_2D_MULTISAMPLE_ARRAY", "GL_TEXTURE_EXTERNAL_OES"})


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
    """The call's arguments checked (the module's rule)."""
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

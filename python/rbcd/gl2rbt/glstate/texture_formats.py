"""Pixel formats and types, texture internal formats, and which image
calls GL certainly takes.

A texture keeps the calls that made its images (textures.py); a call that
GL certainly takes may replace the earlier calls it overwrites (a level
defined again, the same rectangle written again, storage given), and one
GL may refuse must not: it is kept beside them, and Mesa decides when the
calls are replayed. So the checks here answer "certainly taken" only when
every rule GL 4.6 and OpenGL ES 3.2 state for the call holds (sizes,
border, an internal format of the tables, a format and type that go with
it, a level and rectangle of the image as it is), and "not certain"
otherwise: a wrong "not certain" costs memory (bounded by the calls kept a
texture), never an answer."""
import math

# Pixel formats and types (GL 4.5, tables 8.3 to 8.5): components a pixel,
# bytes a component, and the packed types' bytes a pixel.
FORMAT_COMPONENTS = {"GL_RED": 1, "GL_GREEN": 1, "GL_BLUE": 1, "GL_ALPHA": 1, "GL_LUMINANCE": 1,
                     "GL_RED_INTEGER": 1, "GL_GREEN_INTEGER": 1, "GL_BLUE_INTEGER": 1, "GL_ALPHA_INTEGER": 1,
                     "GL_DEPTH_COMPONENT": 1, "GL_STENCIL_INDEX": 1, "GL_DEPTH_STENCIL": 1,
                     "GL_LUMINANCE_ALPHA": 2, "GL_RG": 2, "GL_RG_INTEGER": 2,
                     "GL_RGB": 3, "GL_BGR": 3, "GL_RGB_INTEGER": 3, "GL_BGR_INTEGER": 3,
                     "GL_RGBA": 4, "GL_BGRA": 4, "GL_RGBA_INTEGER": 4, "GL_BGRA_INTEGER": 4}
TYPE_BYTES = {"GL_UNSIGNED_BYTE": 1, "GL_BYTE": 1, "GL_UNSIGNED_SHORT": 2, "GL_SHORT": 2, "GL_UNSIGNED_INT": 4,
              "GL_INT": 4, "GL_HALF_FLOAT": 2, "GL_HALF_FLOAT_OES": 2, "GL_FLOAT": 4}
# Packed types: one element a pixel, of this many bytes.
PACKED_BYTES = {"GL_UNSIGNED_BYTE_3_3_2": 1, "GL_UNSIGNED_BYTE_2_3_3_REV": 1,
                "GL_UNSIGNED_SHORT_5_6_5": 2, "GL_UNSIGNED_SHORT_5_6_5_REV": 2, "GL_UNSIGNED_SHORT_4_4_4_4": 2,
                "GL_UNSIGNED_SHORT_4_4_4_4_REV": 2, "GL_UNSIGNED_SHORT_5_5_5_1": 2,
                "GL_UNSIGNED_SHORT_1_5_5_5_REV": 2, "GL_UNSIGNED_INT_8_8_8_8": 4, "GL_UNSIGNED_INT_8_8_8_8_REV": 4,
                "GL_UNSIGNED_INT_10_10_10_2": 4, "GL_UNSIGNED_INT_2_10_10_10_REV": 4, "GL_UNSIGNED_INT_24_8": 4,
                "GL_UNSIGNED_INT_10F_11F_11F_REV": 4, "GL_UNSIGNED_INT_5_9_9_9_REV": 4,
                "GL_FLOAT_32_UNSIGNED_INT_24_8_REV": 8}


def packed_fits(kind, fmt):
    """A packed type's format (GL 4.5, table 8.5)."""
    if kind in ("GL_UNSIGNED_BYTE_3_3_2", "GL_UNSIGNED_BYTE_2_3_3_REV", "GL_UNSIGNED_SHORT_5_6_5",
                "GL_UNSIGNED_SHORT_5_6_5_REV", "GL_UNSIGNED_INT_10F_11F_11F_REV", "GL_UNSIGNED_INT_5_9_9_9_REV"):
        return fmt in ("GL_RGB", "GL_RGB_INTEGER")
    if kind in ("GL_UNSIGNED_INT_24_8", "GL_FLOAT_32_UNSIGNED_INT_24_8_REV"):
        return fmt == "GL_DEPTH_STENCIL"
    return fmt in ("GL_RGBA", "GL_BGRA", "GL_RGBA_INTEGER", "GL_BGRA_INTEGER")


# The formats an image unit takes (GL 4.6 table 8.26).
IMAGE_FORMATS = {f"GL_{f}" for f in (
    "RGBA32F", "RGBA16F", "RG32F", "RG16F", "R11F_G11F_B10F", "R32F", "R16F", "RGBA32UI", "RGBA16UI", "RGB10_A2UI",
    "RGBA8UI", "RG32UI", "RG16UI", "RG8UI", "R32UI", "R16UI", "R8UI", "RGBA32I", "RGBA16I", "RGBA8I", "RG32I", "RG16I",
    "RG8I", "R32I", "R16I", "R8I", "RGBA16", "RGB10_A2", "RGBA8", "RG16", "RG8", "R16", "R8", "RGBA16_SNORM",
    "RGBA8_SNORM", "RG16_SNORM", "RG8_SNORM", "R16_SNORM", "R8_SNORM")}


# Internal formats by what their pixels hold (GL 4.6, tables 8.11 to 8.13):
# a format of another kind is GL_INVALID_OPERATION.
COLOUR_FORMATS = {"GL_RED", "GL_RG", "GL_RGB", "GL_RGBA"} | {f"GL_{f}" for f in (
    "R8", "R8_SNORM", "R16", "R16_SNORM", "RG8", "RG8_SNORM", "RG16", "RG16_SNORM", "R3_G3_B2", "RGB4", "RGB5",
    "RGB565", "RGB8", "RGB8_SNORM", "RGB10", "RGB12", "RGB16", "RGB16_SNORM", "RGBA2", "RGBA4", "RGB5_A1", "RGBA8",
    "RGBA8_SNORM", "RGB10_A2", "RGBA12", "RGBA16", "RGBA16_SNORM", "SRGB8", "SRGB8_ALPHA8", "R16F", "RG16F",
    "RGB16F", "RGBA16F", "R32F", "RG32F", "RGB32F", "RGBA32F", "R11F_G11F_B10F", "RGB9_E5")}
INTEGER_FORMATS = {f"GL_{c}{b}{s}" for c in ("R", "RG", "RGB", "RGBA") for b in ("8", "16", "32")
                   for s in ("I", "UI")} | {"GL_RGB10_A2UI"}
DEPTH_FORMATS = {"GL_DEPTH_COMPONENT", "GL_DEPTH_COMPONENT16", "GL_DEPTH_COMPONENT24", "GL_DEPTH_COMPONENT32",
                 "GL_DEPTH_COMPONENT32F"}
DEPTH_STENCIL_FORMATS = {"GL_DEPTH_STENCIL", "GL_DEPTH24_STENCIL8", "GL_DEPTH32F_STENCIL8"}
UNSIZED = {"GL_RED", "GL_RG", "GL_RGB", "GL_RGBA", "GL_DEPTH_COMPONENT", "GL_DEPTH_STENCIL"}
# The pixel formats and types of each kind (the integer, depth and depth
# and stencil types kept to those every GL takes).
KIND_PIXELS = {
    "colour": ({"GL_RED", "GL_GREEN", "GL_BLUE", "GL_ALPHA", "GL_RG", "GL_RGB", "GL_BGR", "GL_RGBA", "GL_BGRA"},
               {"GL_UNSIGNED_BYTE", "GL_BYTE", "GL_UNSIGNED_SHORT", "GL_SHORT", "GL_UNSIGNED_INT", "GL_INT",
                "GL_HALF_FLOAT", "GL_FLOAT"} | set(PACKED_BYTES)),
    "integer": ({"GL_RED_INTEGER", "GL_GREEN_INTEGER", "GL_BLUE_INTEGER", "GL_ALPHA_INTEGER", "GL_RG_INTEGER",
                 "GL_RGB_INTEGER", "GL_BGR_INTEGER", "GL_RGBA_INTEGER", "GL_BGRA_INTEGER"},
                {"GL_UNSIGNED_BYTE", "GL_BYTE", "GL_UNSIGNED_SHORT", "GL_SHORT", "GL_UNSIGNED_INT", "GL_INT"}),
    "depth": ({"GL_DEPTH_COMPONENT"}, {"GL_UNSIGNED_SHORT", "GL_UNSIGNED_INT", "GL_FLOAT"}),
    "depth-stencil": ({"GL_DEPTH_STENCIL"}, {"GL_UNSIGNED_INT_24_8", "GL_FLOAT_32_UNSIGNED_INT_24_8_REV"}),
}
# OpenGL ES 3.2's combinations (table 8.2: sized internal format, format,
# type; table 8.3: the unsized ones of ES 2.0, internal format = format).
ES_COMBINATIONS = {
    "GL_RGBA8": {("GL_RGBA", "GL_UNSIGNED_BYTE")}, "GL_RGB5_A1": {
        ("GL_RGBA", "GL_UNSIGNED_BYTE"), ("GL_RGBA", "GL_UNSIGNED_SHORT_5_5_5_1"),
        ("GL_RGBA", "GL_UNSIGNED_INT_2_10_10_10_REV")},
    "GL_RGBA4": {("GL_RGBA", "GL_UNSIGNED_BYTE"), ("GL_RGBA", "GL_UNSIGNED_SHORT_4_4_4_4")},
    "GL_SRGB8_ALPHA8": {("GL_RGBA", "GL_UNSIGNED_BYTE")}, "GL_RGBA8_SNORM": {("GL_RGBA", "GL_BYTE")},
    "GL_RGB10_A2": {("GL_RGBA", "GL_UNSIGNED_INT_2_10_10_10_REV")},
    "GL_RGBA16F": {("GL_RGBA", "GL_HALF_FLOAT"), ("GL_RGBA", "GL_FLOAT")}, "GL_RGBA32F": {("GL_RGBA", "GL_FLOAT")},
    "GL_RGB8": {("GL_RGB", "GL_UNSIGNED_BYTE")}, "GL_SRGB8": {("GL_RGB", "GL_UNSIGNED_BYTE")},
    "GL_RGB565": {("GL_RGB", "GL_UNSIGNED_BYTE"), ("GL_RGB", "GL_UNSIGNED_SHORT_5_6_5")},
    "GL_RGB8_SNORM": {("GL_RGB", "GL_BYTE")},
    "GL_R11F_G11F_B10F": {("GL_RGB", "GL_UNSIGNED_INT_10F_11F_11F_REV"), ("GL_RGB", "GL_HALF_FLOAT"),
                          ("GL_RGB", "GL_FLOAT")},
    "GL_RGB9_E5": {("GL_RGB", "GL_UNSIGNED_INT_5_9_9_9_REV"), ("GL_RGB", "GL_HALF_FLOAT"), ("GL_RGB", "GL_FLOAT")},
    "GL_RGB16F": {("GL_RGB", "GL_HALF_FLOAT"), ("GL_RGB", "GL_FLOAT")}, "GL_RGB32F": {("GL_RGB", "GL_FLOAT")},
    "GL_RG8": {("GL_RG", "GL_UNSIGNED_BYTE")}, "GL_RG8_SNORM": {("GL_RG", "GL_BYTE")},
    "GL_RG16F": {("GL_RG", "GL_HALF_FLOAT"), ("GL_RG", "GL_FLOAT")}, "GL_RG32F": {("GL_RG", "GL_FLOAT")},
    "GL_R8": {("GL_RED", "GL_UNSIGNED_BYTE")}, "GL_R8_SNORM": {("GL_RED", "GL_BYTE")},
    "GL_R16F": {("GL_RED", "GL_HALF_FLOAT"), ("GL_RED", "GL_FLOAT")}, "GL_R32F": {("GL_RED", "GL_FLOAT")},
    "GL_RGB10_A2UI": {("GL_RGBA_INTEGER", "GL_UNSIGNED_INT_2_10_10_10_REV")},
    "GL_DEPTH_COMPONENT16": {("GL_DEPTH_COMPONENT", "GL_UNSIGNED_SHORT"), ("GL_DEPTH_COMPONENT", "GL_UNSIGNED_INT")},
    "GL_DEPTH_COMPONENT24": {("GL_DEPTH_COMPONENT", "GL_UNSIGNED_INT")},
    "GL_DEPTH_COMPONENT32F": {("GL_DEPTH_COMPONENT", "GL_FLOAT")},
    "GL_DEPTH24_STENCIL8": {("GL_DEPTH_STENCIL", "GL_UNSIGNED_INT_24_8")},
    "GL_DEPTH32F_STENCIL8": {("GL_DEPTH_STENCIL", "GL_FLOAT_32_UNSIGNED_INT_24_8_REV")},
} | {f"GL_{c}{b}{s}": {(f"GL_{'RED' if c == 'R' else c}_INTEGER", t)}
     for c in ("R", "RG", "RGB", "RGBA") for b, s, t in (
         ("8", "UI", "GL_UNSIGNED_BYTE"), ("8", "I", "GL_BYTE"), ("16", "UI", "GL_UNSIGNED_SHORT"),
         ("16", "I", "GL_SHORT"), ("32", "UI", "GL_UNSIGNED_INT"), ("32", "I", "GL_INT"))} \
  | {f: {(f, "GL_UNSIGNED_BYTE")} for f in ("GL_RGBA", "GL_RGB", "GL_LUMINANCE_ALPHA", "GL_LUMINANCE", "GL_ALPHA")}
ES_UNSIZED = {"GL_RGBA", "GL_RGB", "GL_LUMINANCE_ALPHA", "GL_LUMINANCE", "GL_ALPHA"}
# Compressed formats every Mesa takes, with their block's size in texels
# and bytes (S3TC, RGTC, BPTC, ETC2/EAC).
COMPRESSED_BLOCKS = {f"GL_COMPRESSED_{n}": b for n, b in (
    ("RGB_S3TC_DXT1_EXT", 8), ("RGBA_S3TC_DXT1_EXT", 8), ("RGBA_S3TC_DXT3_EXT", 16), ("RGBA_S3TC_DXT5_EXT", 16),
    ("SRGB_S3TC_DXT1_EXT", 8), ("SRGB_ALPHA_S3TC_DXT1_EXT", 8), ("SRGB_ALPHA_S3TC_DXT3_EXT", 16),
    ("SRGB_ALPHA_S3TC_DXT5_EXT", 16), ("RED_RGTC1", 8), ("SIGNED_RED_RGTC1", 8), ("RG_RGTC2", 16),
    ("SIGNED_RG_RGTC2", 16), ("RGBA_BPTC_UNORM", 16), ("SRGB_ALPHA_BPTC_UNORM", 16),
    ("RGB_BPTC_SIGNED_FLOAT", 16), ("RGB_BPTC_UNSIGNED_FLOAT", 16), ("RGB8_ETC2", 8), ("SRGB8_ETC2", 8),
    ("RGB8_PUNCHTHROUGH_ALPHA1_ETC2", 8), ("SRGB8_PUNCHTHROUGH_ALPHA1_ETC2", 8), ("RGBA8_ETC2_EAC", 16),
    ("SRGB8_ALPHA8_ETC2_EAC", 16), ("R11_EAC", 8), ("SIGNED_R11_EAC", 8), ("RG11_EAC", 16),
    ("SIGNED_RG11_EAC", 16))}
MAX_SIZE = 16384          # llvmpipe's GL_MAX_TEXTURE_SIZE (the smallest a GL 4 driver has)
MAX_LEVEL = 14            # its last level


# A texture image's digest as a reduced capture carries it in place of the
# pixels: ("rbcd-digest", 16 lower-case hex digits).
DIGEST_TAG = "rbcd-digest"


def is_digest(v):
    return isinstance(v, tuple) and len(v) == 2 and v[0] == DIGEST_TAG and isinstance(v[1], str) \
        and len(v[1]) == 16 and all(c in "0123456789abcdef" for c in v[1])


def kind_of(internalformat):
    for kind, names in (("colour", COLOUR_FORMATS), ("integer", INTEGER_FORMATS), ("depth", DEPTH_FORMATS),
                        ("depth-stencil", DEPTH_STENCIL_FORMATS)):
        if internalformat in names:
            return kind
    return None


def whole(v):
    return isinstance(v, int) and not isinstance(v, bool)


def level_size_fits(d):
    """Whether a call's level, width and height are whole numbers GL takes
    for a 2D level (llvmpipe's 16384 at level 0, halving a level)."""
    lv, w, h = d.get("level"), d.get("width"), d.get("height")
    return all(whole(v) for v in (lv, w, h)) and 0 <= lv <= MAX_LEVEL and 0 <= w <= MAX_SIZE >> lv \
        and 0 <= h <= MAX_SIZE >> lv


def pixels_fit(internalformat, fmt, kind, es, level_type=None):
    """Whether GL certainly takes pixels of format `fmt` and type `kind` for
    an image of `internalformat` (ES: its table; an unsized ES image's
    parts of its own type)."""
    if es:
        if internalformat in ES_UNSIZED and level_type is not None and kind != level_type:
            return False
        return (fmt, kind) in ES_COMBINATIONS.get(internalformat, ())
    k = kind_of(internalformat)
    if k is None:
        return False
    formats, types = KIND_PIXELS[k]
    return fmt in formats and kind in types and (kind not in PACKED_BYTES or packed_fits(kind, fmt))


def compressed_size(internalformat, w, h):
    block = COMPRESSED_BLOCKS.get(internalformat)
    return None if block is None else -(-w // 4) * -(-h // 4) * block


def certain_level(name, d, es):
    """A glTexImage2D or glCompressedTexImage2D GL certainly takes: the
    level's (internal format, width, height, type), or None."""
    fmt, lv, w, h = d.get("internalformat"), d.get("level"), d.get("width"), d.get("height")
    if not (level_size_fits(d) and d.get("border") == 0 and isinstance(fmt, str)):
        return None
    if es and lv and (w & (w - 1) or h & (h - 1)):
        return None   # ES 2.0: a level past 0 of a size not a power of two (without OES_texture_npot)
    if name.startswith("glCompressed"):
        data = d.get("data")
        size = compressed_size(fmt, w, h)
        if size is None or d.get("imageSize") != size or not isinstance(data, (bytes, bytearray)) \
                or len(data) != size:
            return None
        return (fmt, w, h, None)
    if not pixels_fit(fmt, d.get("format"), d.get("type"), es):
        return None
    return (fmt, w, h, d.get("type"))



def certain_part(d, level, es):
    """A glTexSubImage2D GL certainly takes into a level whose (internal
    format, width, height, type) is `level` (None: not known)."""
    if level is None or level[0] in COMPRESSED_BLOCKS:
        return False
    x, y, w, h = (d.get(k) for k in ("xoffset", "yoffset", "width", "height"))
    if not all(whole(v) for v in (x, y, w, h)) or min(x, y, w, h) < 0 or x + w > level[1] or y + h > level[2]:
        return False
    return pixels_fit(level[0], d.get("format"), d.get("type"), es, level[3])


def certain_storage(d):
    """A glTexStorage2D GL certainly takes (on a texture not yet immutable):
    the levels' {level: (internal format, width, height, None)}, or None."""
    fmt, n, w, h = d.get("internalformat"), d.get("levels"), d.get("width"), d.get("height")
    if not (all(whole(v) for v in (n, w, h)) and 1 <= w <= MAX_SIZE and 1 <= h <= MAX_SIZE
            and 1 <= n <= int(math.log2(max(w, h))) + 1 and kind_of(fmt) is not None and fmt not in UNSIZED):
        return None
    return {i: (fmt, max(1, w >> i), max(1, h >> i), None) for i in range(n)}


# ---- what GL certainly refuses (a call that changes nothing: never kept)

def format_kind(fmt):
    """The kind of pixels a format carries (None: not known here)."""
    if fmt in ("GL_LUMINANCE", "GL_LUMINANCE_ALPHA"):
        return "colour"
    return next((k for k, (formats, _) in KIND_PIXELS.items() if fmt in formats), None)


def pixels_refused(internal_kind, d):
    """Whether GL certainly refuses pixels of the call's format and type for
    an image of `internal_kind`: a format or type that is no enumerant, a
    packed type its format does not take, pixels of another kind (integer
    pixels for a normalized image, colour ones for a depth image: GL 4.6,
    8.4.4 and 8.6, GL_INVALID_OPERATION)."""
    fmt, kind = d.get("format"), d.get("type")
    if not isinstance(fmt, str) or not isinstance(kind, str):
        return True
    if kind in PACKED_BYTES and fmt in FORMAT_COMPONENTS and not packed_fits(kind, fmt):
        return True
    # Depth and depth-and-stencil pixels go into either kind of image (GL
    # 4.6, 8.5: both formats must be depth or depth and stencil).
    fk, ik = (("depth" if k == "depth-stencil" else k) for k in (format_kind(fmt), internal_kind))
    return ik is not None and fk is not None and fk != ik


def refused_level(name, d):
    """Whether GL certainly refuses a glTexImage2D (sizes out of range, a
    border past 1, an internal format that is no enumerant, pixels of
    another kind than the internal format's)."""
    fmt = d.get("internalformat")
    if not (level_size_fits(d) and d.get("border") in (0, 1)):
        return True
    if not isinstance(fmt, str) and not (whole(fmt) and 1 <= fmt <= 4):
        return True
    return not name.startswith("glCompressed") and pixels_refused(kind_of(fmt), d)


def refused_part(name, d, level):
    """Whether GL certainly refuses a glTexSubImage2D (or its compressed
    form, whose pixels are not checked here) into a level whose (internal
    format, width, height, type) is `level` (None: not known): a rectangle
    outside it, pixels of another kind."""
    x, y, w, h = (d.get(k) for k in ("xoffset", "yoffset", "width", "height"))
    if not all(whole(v) for v in (x, y, w, h)) or min(w, h) < 0:
        return True
    compressed = name.startswith("glCompressed")
    if level is None:
        return not compressed and pixels_refused(None, d)
    if x < 0 or y < 0 or x + w > level[1] or y + h > level[2]:
        return True
    return not compressed and level[0] not in COMPRESSED_BLOCKS and pixels_refused(kind_of(level[0]), d)


def refused_storage(d):
    """Whether GL certainly refuses a glTexStorage2D: a size or number of
    levels out of range, an internal format of no kind or unsized."""
    fmt, n, w, h = d.get("internalformat"), d.get("levels"), d.get("width"), d.get("height")
    if not (all(whole(v) for v in (n, w, h)) and 1 <= w <= MAX_SIZE and 1 <= h <= MAX_SIZE
            and 1 <= n <= int(math.log2(max(w, h))) + 1):
        return True
    return not isinstance(fmt, str) or fmt in UNSIZED or fmt in ("GL_LUMINANCE", "GL_LUMINANCE_ALPHA", "GL_ALPHA")


def certain_mipmaps(levels, es):
    """Whether glGenerateMipmap certainly regenerates every level past the
    base one (0) of a texture whose known levels are `levels`: a colour
    base image, not compressed (in OpenGL ES one of 8 bits a component
    that its table makes filterable)."""
    base = levels.get(0)
    if base is None or base[0] in COMPRESSED_BLOCKS or kind_of(base[0]) != "colour":
        return False
    return not es or base[0] in ES_UNSIZED | {"GL_RGBA8", "GL_RGB8", "GL_RG8", "GL_R8"}

"""Texture levels as framebuffer completeness reads them (Mesa 22.3,
llvmpipe): each level's image, and of a cube map each face's, with its
size, layers, internal format and samples, for textures of every target;
and what Mesa's completeness test asks of an attached one.

The images come from the calls that give them (glTexImage1D/2D/3D,
glTexStorage1D/2D/3D, their compressed, multisample and direct state
access forms, glGenerateMipmap). A call GL certainly takes gives its
image; one GL certainly refuses changes nothing; any other (a size, format
or pixel type whose acceptance the tables here do not settle, pixels from
a pixel unpack buffer, a copy from the read framebuffer) leaves the image
UNCERTAIN, and a framebuffer it is attached to has a completeness the
converter does not compute (framebuffers.py refuses where that matters).
So does every image of a texture whose levels the converter does not
follow (a view, a base or maximum level set to a value it does not read
as Mesa does, any in OpenGL ES, a mipmap generation it cannot tell Mesa
performs), and every image once the capture holds an image-giving call the
converter passes over. A texture's base and maximum levels are followed
as Mesa sets them: they decide whether an attached level past the base
asks for mipmap completeness, and which levels that reads."""
import math
import re

from ..gl_tables import base_name
from . import parameter_value
from .texture_formats import (COMPRESSED_BLOCKS, KIND_PIXELS, MAX_LEVEL, MAX_SIZE, UNSIZED, certain_level,
                              certain_mipmaps, compressed_size, kind_of, level_size_fits, pixels_fit, refused_level,
                              whole)

# A cube map's faces in layer order (+X, -X, +Y, -Y, +Z, -Z).
CUBE_FACES = tuple(f"GL_TEXTURE_CUBE_MAP_{s}_{a}" for a in "XYZ" for s in ("POSITIVE", "NEGATIVE"))
CUBE = "GL_TEXTURE_CUBE_MAP"
# llvmpipe's limits (GL_MAX_3D_TEXTURE_SIZE, GL_MAX_ARRAY_TEXTURE_LAYERS,
# GL_MAX_SAMPLES: any count from 1 to 4 gives 4, more is refused).
MAX_3D_SIZE = 2048
MAX_LAYERS = 2048
MAX_SAMPLES = 4
# Targets by the shape of a level: a row (1D), a rectangle, a rectangle of
# a cube map's face, rows or rectangles in layers (arrays: a level keeps
# the layers), and a box (3D: a level halves the depth too).
ROW_TARGETS = {"GL_TEXTURE_1D"}
PLANE_TARGETS = {"GL_TEXTURE_2D", "GL_TEXTURE_RECTANGLE", "GL_TEXTURE_2D_MULTISAMPLE"}
ROW_ARRAY = "GL_TEXTURE_1D_ARRAY"
PLANE_ARRAYS = {"GL_TEXTURE_2D_ARRAY", "GL_TEXTURE_CUBE_MAP_ARRAY", "GL_TEXTURE_2D_MULTISAMPLE_ARRAY"}
BOX = "GL_TEXTURE_3D"
SINGLE_LEVEL = {"GL_TEXTURE_RECTANGLE", "GL_TEXTURE_2D_MULTISAMPLE", "GL_TEXTURE_2D_MULTISAMPLE_ARRAY"}
# Targets whose storage takes the compressed formats every Mesa has.
COMPRESSIBLE = {"GL_TEXTURE_2D", "GL_TEXTURE_CUBE_MAP", "GL_TEXTURE_2D_ARRAY", "GL_TEXTURE_CUBE_MAP_ARRAY"}
# The targets each image-giving call takes (bind-to-edit base names); any
# other is GL_INVALID_ENUM or GL_INVALID_OPERATION (a proxy target changes
# no texture).
PLANE_CALL_TARGETS = {"GL_TEXTURE_2D", "GL_TEXTURE_RECTANGLE", "GL_TEXTURE_1D_ARRAY"} | set(CUBE_FACES)
CALL_TARGETS = {
    "glTexImage1D": {"GL_TEXTURE_1D"}, "glCompressedTexImage1D": {"GL_TEXTURE_1D"},
    "glCopyTexImage1D": {"GL_TEXTURE_1D"}, "glTexStorage1D": {"GL_TEXTURE_1D"},
    "glTexImage2D": PLANE_CALL_TARGETS, "glCompressedTexImage2D": PLANE_CALL_TARGETS,
    "glCopyTexImage2D": PLANE_CALL_TARGETS,
    "glTexStorage2D": {"GL_TEXTURE_2D", "GL_TEXTURE_RECTANGLE", "GL_TEXTURE_1D_ARRAY", CUBE},
    "glTexImage3D": {"GL_TEXTURE_3D", "GL_TEXTURE_2D_ARRAY", "GL_TEXTURE_CUBE_MAP_ARRAY"},
    "glCompressedTexImage3D": {"GL_TEXTURE_3D", "GL_TEXTURE_2D_ARRAY", "GL_TEXTURE_CUBE_MAP_ARRAY"},
    "glTexStorage3D": {"GL_TEXTURE_3D", "GL_TEXTURE_2D_ARRAY", "GL_TEXTURE_CUBE_MAP_ARRAY"},
    "glTexImage2DMultisample": {"GL_TEXTURE_2D_MULTISAMPLE"},
    "glTexStorage2DMultisample": {"GL_TEXTURE_2D_MULTISAMPLE"},
    "glTexImage3DMultisample": {"GL_TEXTURE_2D_MULTISAMPLE_ARRAY"},
    "glTexStorage3DMultisample": {"GL_TEXTURE_2D_MULTISAMPLE_ARRAY"},
}
# Image-giving calls the converter passes over (EXT_direct_state_access's
# compressed and copy forms, storage in external memory, a window system's
# drawable bound as a texture): after one, no texture's images are known.
PASSED_OVER_IMAGES = re.compile(r"^(gl(Compressed|Copy)?Tex(ture)?(Image|Storage)(Mem)?\d|(glX|egl|wgl)BindTexImage)")
# The targets whose images reduced captures before version 5 kept (those
# of glTexImage2D, glTexStorage2D and their kin).
PLANE_IMAGES = {"GL_TEXTURE_2D", "GL_TEXTURE_RECTANGLE", "GL_TEXTURE_2D_MULTISAMPLE", "GL_TEXTURE_CUBE_MAP",
                "GL_TEXTURE_1D_ARRAY"}
# What an UNCERTAIN image or an unfollowed texture makes of an attachment.
UNCERTAIN = "uncertain"


class TextureLevels:
    """One texture's images as completeness reads them: `images[(level,
    face)]` = (width, height, layers, internal format, samples, fixed
    sample locations), or UNCERTAIN; `target`; `immutable`: the levels of
    its storage (None: mutable); `unfollowed`: why its images are not
    known (None: they are); `base_level`, `max_level`: GL_TEXTURE_BASE_LEVEL
    and GL_TEXTURE_MAX_LEVEL as Mesa keeps them."""
    __slots__ = ("target", "images", "immutable", "unfollowed", "base_level", "max_level")

    def __init__(self, target):
        self.target, self.images, self.immutable, self.unfollowed = target, {}, None, None
        self.base_level, self.max_level = 0, DEFAULT_MAX_LEVEL


# glTextureView: the targets a view of each target may have (GL 4.6 table
# 8.21), and the view classes of the uncompressed formats (table 8.22): a
# view's format is the texture's or one of its class. Other formats
# (compressed, depth) the converter does not follow in a view.
VIEW_TARGETS = {
    "GL_TEXTURE_1D": {"GL_TEXTURE_1D", ROW_ARRAY}, ROW_ARRAY: {"GL_TEXTURE_1D", ROW_ARRAY},
    "GL_TEXTURE_2D": {"GL_TEXTURE_2D", "GL_TEXTURE_2D_ARRAY"}, BOX: {BOX},
    "GL_TEXTURE_RECTANGLE": {"GL_TEXTURE_RECTANGLE"},
    **dict.fromkeys((CUBE, "GL_TEXTURE_2D_ARRAY", "GL_TEXTURE_CUBE_MAP_ARRAY"),
                    {"GL_TEXTURE_2D", "GL_TEXTURE_2D_ARRAY", CUBE, "GL_TEXTURE_CUBE_MAP_ARRAY"}),
    **dict.fromkeys(("GL_TEXTURE_2D_MULTISAMPLE", "GL_TEXTURE_2D_MULTISAMPLE_ARRAY"),
                    {"GL_TEXTURE_2D_MULTISAMPLE", "GL_TEXTURE_2D_MULTISAMPLE_ARRAY"})}
VIEW_CLASSES = {f"GL_{f}": bits for bits, names in (
    (128, "RGBA32F RGBA32UI RGBA32I"), (96, "RGB32F RGB32UI RGB32I"),
    (64, "RGBA16F RG32F RGBA16UI RG32UI RGBA16I RG32I RGBA16 RGBA16_SNORM"),
    (48, "RGB16 RGB16_SNORM RGB16F RGB16UI RGB16I"),
    (32, "RG16F R11F_G11F_B10F R32F RGB10_A2UI RGBA8UI RG16UI R32UI RGBA8I RG16I R32I RGB10_A2 RGBA8 RG16 "
         "RGBA8_SNORM RG16_SNORM SRGB8_ALPHA8 RGB9_E5"),
    (24, "RGB8 RGB8_SNORM SRGB8 RGB8UI RGB8I"),
    (16, "R16F RG8UI R16UI RG8I R16I RG8 R16 RG8_SNORM R16_SNORM"),
    (8, "R8UI R8I R8 R8_SNORM")) for f in names.split()}
CUBE_VIEW_SIZE = 8192   # llvmpipe's GL_MAX_CUBE_MAP_TEXTURE_SIZE
DEFAULT_MAX_LEVEL = 1000   # GL_TEXTURE_MAX_LEVEL's initial value
LEVEL_RANGE = {"GL_TEXTURE_BASE_LEVEL": "base_level", 0x813C: "base_level", "GL_TEXTURE_MAX_LEVEL": "max_level",
               0x813D: "max_level"}


def faces_of(target):
    return range(6) if target == CUBE else (0,)


def level_extent(target, d):
    """(width, height, layers) a level-giving call's arguments name for a
    texture of `target` (a 1D array's layers are its rows)."""
    w, h, depth = d.get("width"), d.get("height", 1), d.get("depth", 1)
    if target == ROW_ARRAY:
        return w, 1, h
    return w, h, depth


def extent_fits(target, level, w, h, layers):
    """Whether GL takes this size at this level (llvmpipe's limits; a cube
    map's faces are square)."""
    if not (all(whole(v) for v in (level, w, h, layers)) and 0 <= level <= MAX_LEVEL):
        return False
    if target == BOX:
        top = MAX_3D_SIZE >> level
        return 0 <= w <= top and 0 <= h <= top and 0 <= layers <= top
    top = MAX_SIZE >> level
    return 0 <= w <= top and 0 <= h <= top and 0 <= layers <= MAX_LAYERS and (target != CUBE or w == h)


def chain(target, w, h, layers, levels):
    """Level i's (width, height, layers) for levels 0..levels-1 of a
    mipmap chain from (w, h, layers)."""
    for i in range(levels):
        yield i, (max(1, w >> i), max(1, h >> i), max(1, layers >> i) if target == BOX else layers)


def unguessable(target, image):
    """Whether Mesa's state tracker cannot tell a 2D or 3D texture's level-0
    size from this image of a level past 0 (st_cb_texture.c's guess: one
    texel wide or high, or deep for 3D). Round 30's cases against Mesa: such
    an image attached at its base level is GL_FRAMEBUFFER_UNSUPPORTED; a 1D
    texture's and a cube map's are complete."""
    w, h, layers = image[:3]
    return target in ("GL_TEXTURE_2D", BOX) and (w == 1 or h == 1 or target == BOX and layers == 1)


def chain_length(target, w, h, layers):
    """The levels of a complete mipmap chain from a base of this size."""
    if target in SINGLE_LEVEL:
        return 1
    largest = max(w, layers if target == BOX else 1, h if target not in ROW_TARGETS | {ROW_ARRAY} else 1)
    return int(math.log2(largest)) + 1 if largest > 0 else 0


def certain_image(name, target, d, es):
    """A glTexImage*, glCompressedTexImage* or multisample image call GL
    certainly takes: its image's (width, height, layers, internal format,
    samples, fixed sample locations); "refused" when GL certainly refuses
    it; None otherwise."""
    fmt = d.get("internalformat")
    shape = CUBE if target in CUBE_FACES else target
    w, h, layers = level_extent(shape, d)
    if not all(whole(v) for v in (w, h, layers)) or min(w, h, layers) < 0:
        return "refused"   # (GL_INVALID_VALUE)
    if shape == CUBE and w != h:
        return "refused"   # (a cube map's face is square: GL_INVALID_VALUE)
    if "Multisample" in name:
        samples = d.get("samples")
        if not whole(samples) or samples < 1:
            return "refused"   # (GL_INVALID_VALUE; glretrace's replay asks at most llvmpipe's 4, which it gives)
        if extent_fits(shape, 0, w, h, layers) and kind_of(fmt) is not None and fmt not in UNSIZED:
            return (w, h, layers, fmt, MAX_SAMPLES, d.get("fixedsamplelocations") not in (0, False, "GL_FALSE"))
        return None
    plane = dict(d, width=w, height=h)
    if refused_level(name.replace("1D", "2D").replace("3D", "2D"), plane):
        return "refused"
    if not name.startswith("glCompressed") and isinstance(fmt, str) and ("ETC2" in fmt or fmt.endswith("_EAC")):
        return "refused"   # (pixels Mesa does not compress: GL_INVALID_OPERATION)
    if not extent_fits(shape, d.get("level"), w, h, layers):
        return None
    if name.startswith("glCompressed"):
        # Compressed images of a plane alone are checked (the block sizes).
        if shape not in PLANE_TARGETS and shape != CUBE:
            return None
        if isinstance(d.get("data"), tuple):
            # A reduced capture's digest in the pixels' place: apitrace
            # recorded imageSize bytes, the size the format's blocks make.
            level = d.get("level")
            taken = level_size_fits(d) and d.get("border") == 0 and fmt in COMPRESSED_BLOCKS \
                and d.get("imageSize") == compressed_size(fmt, w, h) \
                and not (es and level and (w & (w - 1) or h & (h - 1)))
        else:
            taken = certain_level(name, d, es) is not None
        return (w, h, 1, fmt, 0, True) if taken else None
    if shape == BOX and kind_of(fmt) in ("depth", "depth-stencil"):
        return "refused"   # (a depth image of a 3D texture: GL_INVALID_OPERATION)
    if d.get("border") != 0 or not isinstance(fmt, str) or kind_of(fmt) is None:
        return None
    pixels = d.get("format")
    if not es and kind_of(fmt) in ("depth", "depth-stencil") and pixels in ("GL_DEPTH_COMPONENT", "GL_DEPTH_STENCIL"):
        # (depth pixels into a depth-and-stencil image and the reverse are
        # taken: GL 4.6, 8.5)
        if d.get("type") not in KIND_PIXELS["depth" if pixels == "GL_DEPTH_COMPONENT" else "depth-stencil"][1]:
            return None
    elif not pixels_fit(fmt, pixels, d.get("type"), es):
        return None
    return (w, h, layers, fmt, 0, True)


def certain_storage_levels(name, target, d, es):
    """A glTexStorage* GL certainly takes: {level: image} of every level
    (of each face); "refused" when GL certainly refuses it; None
    otherwise (GL may take it: the texture is immutable, its images not
    known)."""
    if "Multisample" in name:
        image = certain_image(name, target, d, es)
        return image if image in (None, "refused") else {0: image}
    levels, fmt = d.get("levels"), d.get("internalformat")
    w, h, layers = level_extent(target, d)
    if not all(whole(v) for v in (levels, w, h, layers)) or min(levels, w, h, layers) < 1 \
            or levels > chain_length(target, w, h, layers) or not extent_fits(target, 0, w, h, layers) \
            or not isinstance(fmt, str) or fmt in UNSIZED or fmt in ("GL_LUMINANCE", "GL_LUMINANCE_ALPHA",
                                                                       "GL_ALPHA"):
        return "refused"   # (GL_INVALID_VALUE, GL_INVALID_OPERATION or GL_INVALID_ENUM)
    if target == BOX and kind_of(fmt) in ("depth", "depth-stencil"):
        return "refused"
    if fmt in COMPRESSED_BLOCKS and target in COMPRESSIBLE:
        pass   # (compressed storage of a plane or an array of planes: taken)
    elif kind_of(fmt) is None:
        return None
    return {level: extent + (fmt, 0, True) for level, extent in chain(target, w, h, layers, levels)}


class TextureLevelCalls:
    """self.s.texture_levels[("texture", name)] = TextureLevels (a deleted
    texture that lives on for a framebuffer: under its kept name, as
    framebuffers.detach_deleted renames it); self.s.images_passed_over:
    (call, name) of an image-giving call the converter passes over."""

    def texture_levels(self, tex, target):
        img = ("texture", tex)
        tl = self.s.texture_levels.get(img)
        if tl is None:
            tl = self.s.texture_levels[img] = TextureLevels(self.s.texture_targets.get(tex, target))
        return tl

    def record_levels(self, no, name, d):
        """An image-giving call (its bind-to-edit base name) on the texture
        bound at its target: the images it gives, or UNCERTAIN ones.
        Whether GL may have taken it (False: it certainly refuses it, or the
        texture is immutable, and nothing changes)."""
        target = d.get("target")
        bound = CUBE if target in CUBE_FACES else target
        if not isinstance(bound, str) or target not in CALL_TARGETS.get(name, ()):
            return False   # (a target the call does not take, or a proxy: the call changes no texture)
        tex = self.bound_texture(bound)
        if not tex:
            return True   # (the default texture: never attached)
        tl = self.texture_levels(tex, bound)
        if tl.immutable is not None:
            return False   # GL_INVALID_OPERATION: storage stays
        if "Storage" in name:
            levels = certain_storage_levels(name, bound, d, self.es)
            if levels == "refused":
                return False
            tl.images = {}
            if levels is None:
                # (whether the texture is immutable is not known either)
                tl.unfollowed = f"storage (call {no}, {name}) the converter cannot tell GL gave"
            else:
                tl.immutable = 1 if "Multisample" in name else d["levels"]
                for level, image in levels.items():
                    for face in faces_of(bound):
                        tl.images[(level, face)] = image
            return True
        level = d.get("level", 0)
        face = CUBE_FACES.index(target) if target in CUBE_FACES else 0
        if bound == CUBE and target not in CUBE_FACES or bound in SINGLE_LEVEL and level != 0:
            return False   # GL_INVALID_ENUM or GL_INVALID_VALUE
        if name.startswith("glCopy"):
            if not (whole(level) and 0 <= level <= MAX_LEVEL):
                return False
            old = tl.images.get((level, face))
            if old not in (None, UNCERTAIN) and old[:2] == (d.get("width"), d.get("height", 1)) \
                    and old[3:5] == (d.get("internalformat"), 0):
                return False   # (Mesa copies into the level as it is: no new image)
            taken = None   # (whether Mesa takes it depends on the read framebuffer)
        else:
            taken = certain_image(name, target, d, self.es)
            if taken != "refused" and self.s.bound.get("GL_PIXEL_UNPACK_BUFFER", 0):
                taken = None   # (Mesa refuses a pixel unpack buffer too small for the image)
        if taken == "refused":
            return False
        tl.images[(level, face)] = UNCERTAIN if taken is None else taken
        return True

    def record_mipmaps(self, no, name, d):
        """glGenerateMipmap: every level past 0 made from level 0, when GL
        certainly does (a colour base image, not compressed, of every face
        alike, no base or maximum level set); otherwise the texture's
        levels are no longer known. A texture without a base image is left
        as it was (Mesa makes nothing)."""
        target = d.get("target")
        if not isinstance(target, str):
            return
        tex = self.bound_texture(target)
        tl = self.s.texture_levels.get(("texture", tex)) if tex else None
        if tl is None or tl.unfollowed or tl.immutable is not None and tl.immutable <= 1:
            return
        if (tl.base_level, tl.max_level) != (0, DEFAULT_MAX_LEVEL):
            tl.unfollowed = f"a mipmap generation (call {no}) with a base or maximum level set"
            return
        base = [tl.images.get((0, f)) for f in faces_of(target)]
        if all(b is None for b in base):
            return
        if any(b is None or b is UNCERTAIN for b in base) or len({b[:4] for b in base}) > 1 \
                or target in SINGLE_LEVEL or not certain_mipmaps({0: base[0][3:4]}, self.es):
            tl.unfollowed = f"a mipmap generation (call {no}) the converter cannot tell GL performs"
            return
        w, h, layers, fmt, _, _ = base[0]
        last = tl.immutable if tl.immutable is not None else chain_length(target, w, h, layers)
        for level, extent in chain(target, w, h, layers, last):
            if level:
                for face in faces_of(target):
                    tl.images[(level, face)] = extent + (fmt, 0, True)

    def level_range_set(self, d):
        """glTexParameter* of GL_TEXTURE_BASE_LEVEL or GL_TEXTURE_MAX_LEVEL
        (which levels completeness reads) as Mesa 22.3 sets them
        (texparam.c): a negative value, a base level past 0 of a rectangle
        or multisample texture and a maximum past 0 of a rectangle one are
        refused (nothing changes); an immutable texture's are clamped to its
        levels (the maximum to the base level and above). A value the
        converter does not read as Mesa does (not a whole number of a
        GLint), or either set in OpenGL ES (whose versions differ), leaves
        the texture's levels unfollowed."""
        pname = d.get("pname")
        attr = LEVEL_RANGE.get(pname) if isinstance(pname, (str, int)) else None
        target = d.get("target")
        tex = self.bound_texture(target) if attr and isinstance(target, str) else 0
        if not tex:
            return
        tl = self.texture_levels(tex, target)
        value = parameter_value(d)
        if isinstance(value, float) and value.is_integer():
            value = int(value)
        if self.es or not whole(value) or not -(1 << 31) <= value < 1 << 31:
            tl.unfollowed = "a base or maximum level set"
            return
        if value < 0 or value > 0 and (tl.target == "GL_TEXTURE_RECTANGLE" or attr == "base_level"
                                       and tl.target in ("GL_TEXTURE_2D_MULTISAMPLE",
                                                         "GL_TEXTURE_2D_MULTISAMPLE_ARRAY")):
            return   # (GL_INVALID_VALUE or GL_INVALID_OPERATION)
        if tl.immutable is not None:
            last = tl.immutable - 1
            value = min(last, value) if attr == "base_level" else max(tl.base_level, min(value, last))
        setattr(tl, attr, value)

    def record_view(self, d):
        """glTextureView(texture, target, origtexture, internalformat,
        minlevel, numlevels, minlayer, numlayers) as Mesa 22.3 makes it:
        "view" when GL certainly makes texture a view of origtexture's
        images (its levels and layers, in the format given: its images
        recorded, immutable as the original is), "refused" when GL certainly
        refuses it (nothing changes), None when the converter cannot tell
        (a name it did not see generated, an original whose images it does
        not follow, a compressed or depth format, an empty range)."""
        view, orig, target, fmt = d.get("texture"), d.get("origtexture"), d.get("target"), d.get("internalformat")
        minlevel, numlevels, minlayer, numlayers = (d.get(k) for k in ("minlevel", "numlevels", "minlayer",
                                                                        "numlayers"))
        if not all(whole(v) for v in (view, orig, minlevel, numlevels, minlayer, numlayers)):
            return None
        if not orig or not view:
            return "refused"   # (GL_INVALID_VALUE)
        tl = self.s.texture_levels.get(("texture", orig))
        if tl is None or self.unknown_images(("texture", orig)) or self.s.texture_names is None \
                or view not in self.s.texture_names:
            return None
        if tl.immutable is None:
            return "refused" if orig in self.s.texture_targets else None   # (not immutable: GL_INVALID_OPERATION)
        if view in self.s.texture_targets:
            return "refused"   # (a texture bound before: GL_INVALID_OPERATION)
        if target not in VIEW_TARGETS.get(tl.target, ()):
            return "refused" if isinstance(target, str) and target in VIEW_TARGETS else None
        levels = 1 + max((lv for lv, _ in tl.images), default=-1)   # (an immutable texture's: all given)
        if minlevel >= levels:
            return "refused" if levels > 0 else None   # (GL_INVALID_VALUE)
        base = [tl.images.get((minlevel, f)) for f in faces_of(tl.target)]
        if any(b is None or b is UNCERTAIN for b in base):
            return None
        layers = 6 if tl.target == CUBE else base[0][2] if tl.target in PLANE_ARRAYS | {ROW_ARRAY} else 1
        if minlayer >= layers:
            return "refused"   # (GL_INVALID_VALUE)
        own = base[0][3]
        if fmt not in VIEW_CLASSES:
            return None   # (a depth or compressed view: its contents are followed no further)
        if VIEW_CLASSES[fmt] != VIEW_CLASSES.get(own):
            return "refused" if own in VIEW_CLASSES else None   # (another class: GL_INVALID_OPERATION)
        new_levels, new_layers = min(numlevels, levels - minlevel), min(numlayers, layers - minlayer)
        if new_levels < 1 or new_layers < 1:
            return None
        if target in (CUBE, "GL_TEXTURE_CUBE_MAP_ARRAY"):
            if new_layers % 6 or target == CUBE and new_layers != 6:
                return "refused"   # (GL_INVALID_VALUE)
            if base[0][0] != base[0][1] or base[0][0] > CUBE_VIEW_SIZE:
                return "refused" if base[0][0] != base[0][1] else None   # (GL_INVALID_OPERATION)
        elif target not in PLANE_ARRAYS | {ROW_ARRAY} and numlayers != 1:
            return "refused"   # (GL_INVALID_VALUE: the argument, not its clamped value)
        vl = self.s.texture_levels[("texture", view)] = TextureLevels(target)
        vl.immutable = tl.immutable   # (Mesa: the original's immutable levels)
        for i in range(new_levels):
            for face in faces_of(target):
                if tl.target == CUBE:
                    image = tl.images.get((minlevel + i, minlayer + face))
                else:
                    image = tl.images.get((minlevel + i, 0))
                if image is None or image is UNCERTAIN:
                    vl.unfollowed = "a view of an image the converter cannot tell GL gave"
                    return "view"
                if target in PLANE_ARRAYS | {ROW_ARRAY}:
                    count = new_layers
                else:
                    count = image[2] if target == BOX else 1
                vl.images[(i, face)] = image[:2] + (count, fmt) + image[4:]
        return "view"

    def levels_unfollowed(self, tex, why):
        self.texture_levels(tex, self.s.texture_targets.get(tex)).unfollowed = why

    def unknown_images(self, img):
        """Why texture `img`'s images are not known (a str), or None: an
        image-giving call passed over, a reduced capture that kept no 1D,
        3D or array images, a texture whose levels are not followed."""
        if self.s.images_passed_over is not None:
            no, name = self.s.images_passed_over
            return f"call {no} ({name}) gives texture images the converter does not follow"
        tl = self.s.texture_levels.get(img)
        if not self.every_image_shown and (tl.target if tl is not None else self.s.texture_targets.get(img[1])) \
                not in PLANE_IMAGES:
            return "a reduced capture of version 4 or earlier, which kept no 1D, 3D or array texture's images"
        return tl.unfollowed if tl is not None else None

    def plane_size(self, key):
        """The (width, height) of texture attachment `key`, one level of a
        texture without layers or faces (framebuffers.py's keys without
        "layer"), as GL draws into it: None when that level has no image;
        why it is not known (a str)."""
        img, level = key[:2], key[2] if len(key) > 2 and whole(key[2]) else 0
        tl = self.s.texture_levels.get(img)
        image = tl.images.get((level, 0)) if tl is not None else None
        if image is None or image is UNCERTAIN:
            # (no image: GL never gave one, unless its images are not followed)
            return self.unknown_images(img) or (None if image is None else "an image the converter cannot tell GL gave")
        return image[:2]

    def attached_image(self, key):
        """The image a texture attachment `key` (framebuffers.py's keys)
        names, as Mesa's completeness test reads it: its (width, height,
        layers, internal format, samples, fixed locations); False when
        that makes the framebuffer incomplete (no image, an empty one, a
        layer past the texture's, a layered cube map whose faces differ, a
        level past 0 of a mutable texture that is not mipmap complete); or
        why it is not known (a str)."""
        img, level = key[:2], key[2] if len(key) > 2 and whole(key[2]) else 0
        layer = key[key.index("layer") + 1] if "layer" in key else None
        unknown = self.unknown_images(img)
        if unknown:
            return unknown
        tl = self.s.texture_levels.get(img)
        if tl is None:
            return False
        if tl.immutable is None and tl.target in PLANE_ARRAYS and any(
                lv > 0 and image is not UNCERTAIN and min(image[:2]) == 1 for (lv, _), image in tl.images.items()):
            # (Mesa's state tracker keeps such an image apart from the
            # texture's storage, and llvmpipe then finds attachments of
            # the texture unsupported: not followed)
            return "an array texture's level past 0 one texel wide or high"
        if tl.immutable is None and len({i[3] for i in tl.images.values() if i is not UNCERTAIN}) > 1:
            # (Mesa's state tracker keeps such a texture's images in
            # storages of their own as they come, and llvmpipe validates an
            # attachment by the format of the texture's main storage: not
            # followed)
            return "a texture with images of more than one format"
        face = CUBE_FACES.index(layer) if isinstance(layer, str) and layer in CUBE_FACES else \
            layer if tl.target == CUBE and whole(layer) else 0
        image = tl.images.get((level, face))
        if image is UNCERTAIN:
            return "an image the converter cannot tell GL gave"
        if image is None or min(image[:3]) <= 0:
            return False
        if layer == "all" and tl.target == CUBE:
            # A layered cube map: face 0's image, and a cube complete at
            # its base level (Mesa's _mesa_cube_complete).
            base = [tl.images.get((tl.base_level, f)) for f in range(6)]
            if any(b is UNCERTAIN for b in base):
                return "an image the converter cannot tell GL gave"
            if any(b is None for b in base) or len({b[:4] for b in base}) > 1:
                return False
        if whole(layer) and tl.target != CUBE and tl.target != "GL_TEXTURE_2D_MULTISAMPLE_ARRAY" \
                and layer >= image[2]:
            return False   # (Mesa does not compare a multisample array's layer)
        if level > tl.base_level:
            # (Mesa asks a level past the base for mipmap completeness; an
            # immutable texture's is that its base image exists and its
            # maximum level is not below it)
            complete = self.mipmap_complete(tl) if tl.immutable is None else \
                tl.base_level < tl.immutable and tl.max_level >= tl.base_level
            if complete is not True:
                return complete
        if tl.immutable is None and tl.base_level > 0 and level > 0 and unguessable(tl.target, image):
            # (Mesa's state tracker cannot tell level 0's size from such an
            # image, keeps it apart from the texture's storage, and llvmpipe
            # finds the attachment unsupported, where the rest of the test
            # passes: not followed)
            return "a level past 0 one texel wide, high or deep, of a 2D or 3D texture whose base level is past 0"
        return image

    @staticmethod
    def mipmap_complete(tl):
        """Mesa's mipmap completeness of a mutable texture
        (_mesa_test_texobj_completeness): a maximum level not below the
        base level, a base image of each face alike and not empty, and every
        level past it the chain from it names, up to the maximum level, of
        each face, of the chain's size and the base's format."""
        first, most = tl.base_level, tl.max_level
        if most < first:
            return False
        base = [tl.images.get((first, f)) for f in faces_of(tl.target)]
        if any(b is UNCERTAIN for b in base):
            return "an image the converter cannot tell GL gave"
        if any(b is None for b in base) or len({b[:4] for b in base}) > 1 or min(base[0][:3]) <= 0:
            return False
        w, h, layers, fmt = base[0][:4]
        count = min(chain_length(tl.target, w, h, layers), most - first + 1, MAX_LEVEL - first + 1)
        for step, extent in chain(tl.target, w, h, layers, count):
            level = first + step
            for face in faces_of(tl.target):
                image = tl.images.get((level, face))
                if image is UNCERTAIN:
                    return "an image the converter cannot tell GL gave"
                if image is None or image[:4] != extent + (fmt,):
                    return False
        return True

    def h_tex_image_any(self, no, name, a, args):
        """glTexImage1D/3D, glCompressedTexImage1D/3D, glTexStorage1D/3D,
        glTexImage3DMultisample, glTexStorage3DMultisample, glCopyTexImage1D
        (glTexImage2D's kin: FramebufferCalls.h_tex_image): a texture of a
        target other than 2D is read back again from Mesa's replay when a
        vertex shader reads it (rendered_textures); the images it gives
        are recorded, and clear the status of the framebuffers they are
        attached to."""
        d = dict(args)
        self.gpu_wrote()
        if self.record_levels(no, base_name(name), d):
            self.texture_levels_changed(d)

    HANDLERS = {
        "glTexImage1D": h_tex_image_any,
        "glTexImage3D": h_tex_image_any,
        "glCompressedTexImage1D": h_tex_image_any,
        "glCompressedTexImage3D": h_tex_image_any,
        "glTexStorage1D": h_tex_image_any,
        "glTexStorage3D": h_tex_image_any,
        "glTexImage3DMultisample": h_tex_image_any,
        "glTexStorage3DMultisample": h_tex_image_any,
        "glCopyTexImage1D": h_tex_image_any,
    }

"""Framebuffer objects and textures: which pass a draw belongs to, and the
texture buffers a vertex shader reads.

The unit sees the frame's camera pass, where a tile-based GPU would run it:
draws into the window's framebuffer, or into a framebuffer object whose depth
attachment has the screen's size (a deferred renderer's geometry pass).
Draws into other targets (shadow maps, reflections, cube maps, post
processing at other sizes) are GPU work of their own, left out of the trace
and counted (docs/gl-capture.md, "Which pass")."""
import hashlib

from ...cli import I32, I64, U32, integer
from ..errors import checked, fail_call, printable
from ..gl_tables import base_name
from . import bitfield, generated_name
from .image_calls import TEXTURE_TARGETS
from .texture_formats import (DEPTH_FORMATS, DEPTH_STENCIL_FORMATS, INTEGER_FORMATS, MAX_LEVEL,
                              is_digest, refused_level, refused_storage)
from .texture_levels import BOX, CUBE, CUBE_FACES, MAX_3D_SIZE, MAX_LAYERS, MAX_SAMPLES, SINGLE_LEVEL, UNCERTAIN

DEPTH_ATTACHMENTS = ("GL_DEPTH_ATTACHMENT", "GL_DEPTH_STENCIL_ATTACHMENT")
# The other attachment points (llvmpipe's GL_MAX_COLOR_ATTACHMENTS: 8).
OTHER_ATTACHMENTS = tuple(f"GL_COLOR_ATTACHMENT{i}" for i in range(8)) + ("GL_STENCIL_ATTACHMENT",)
# The targets glBindTexture takes are image_calls.TEXTURE_TARGETS (Mesa
# 22.3's _mesa_tex_target_to_index): 1D, 1D arrays and rectangles only in
# desktop GL, external images only in OpenGL ES; another is GL_INVALID_ENUM,
# a proxy target too.
DESKTOP_BIND_TARGETS = {"GL_TEXTURE_1D", "GL_TEXTURE_1D_ARRAY", "GL_TEXTURE_RECTANGLE"}
GL_TEXTURE0 = 0x84C0
MAX_TEXTURE_UNITS = 192   # llvmpipe's GL_MAX_COMBINED_TEXTURE_IMAGE_UNITS
MAX_RENDERBUFFER_SIZE = 16384   # llvmpipe's GL_MAX_RENDERBUFFER_SIZE
# A framebuffer object's completeness status (GLState.fbo_status) before a
# test, and the test's answer when the converter cannot compute Mesa's: a
# reason (a str) in place of True or False.
UNTESTED = None
# Internal formats certainly colour-renderable in llvmpipe (GL 4.6 table
# 8.12's required ones); the others are not computed, except compressed and
# shared-exponent ones, never renderable.
RENDERABLE = {f"GL_{f}" for f in (
    "RED", "RG", "RGB", "RGBA", "R8", "RG8", "RGB8", "RGBA8", "R16", "RG16", "RGBA16", "R16F", "RG16F", "RGBA16F",
    "R32F", "RG32F", "RGBA32F", "R11F_G11F_B10F", "RGB10_A2", "RGB10_A2UI", "SRGB8_ALPHA8")} | {
    f"GL_{c}{b}{s}" for c in ("R", "RG", "RGBA") for b in ("8", "16", "32") for s in ("I", "UI")} | {3, 4}
# And those a desktop GL context (core or compatibility) renders too, as
# Mesa 22.3 and llvmpipe find them complete, texture and renderbuffer
# alike (OpenGL ES renders fewer: RENDERABLE there).
DESKTOP_RENDERABLE = RENDERABLE | {f"GL_{f}" for f in (
    "RGB16F", "RGB32F", "R8_SNORM", "RG8_SNORM", "RGBA8_SNORM", "R16_SNORM", "RG16_SNORM", "RGBA16_SNORM",
    "RGB565", "RGBA4", "RGB5_A1", "SRGB8", "RGB16", "RGB8I", "RGB8UI", "RGB16I", "RGB16UI", "RGB32I", "RGB32UI",
    "R3_G3_B2", "RGB4", "RGB5", "RGB10", "RGB12", "RGBA2", "RGBA12")}
# The internal formats glTexBuffer takes in Mesa 22.3 (GL 4.5's table 8.18);
# a compatibility context also the legacy ones. Another is GL_INVALID_ENUM.
TEXTURE_BUFFER_FORMATS = {f"GL_{c}{b}{t}" for c in ("R", "RG", "RGBA") for b, ts in
                          (("8", ("", "I", "UI")), ("16", ("", "F", "I", "UI")), ("32", ("F", "I", "UI")))
                          for t in ts} | {"GL_RGB32F", "GL_RGB32I", "GL_RGB32UI"}
LEGACY_TEXTURE_BUFFER_FORMATS = {f"GL_{c}{b}" for c in ("ALPHA", "INTENSITY", "LUMINANCE") for b in ("8", "16")} \
    | {"GL_LUMINANCE8_ALPHA8", "GL_LUMINANCE16_ALPHA16"}


def texture_image_digest(d):
    """The digest of an image call's level-0 image (glTexImage2D's, and a
    reduced capture's glTexImage1D/3D: its size, formats and
    pixels; 16 hex digits), or None when the call carries no pixels (NULL,
    a pixel unpack buffer's offset, or a reduced capture written without
    them). Selection rules name textures by it (`texture_image`): unlike the
    GL name, it does not depend on the order the game loads its textures,
    so one rule names a kart's texture on every track."""
    pixels = d.get("pixels", d.get("data"))
    if isinstance(pixels, tuple):
        # A reduced capture's digest; anything else in its place is the
        # file's error (the handler's net names the call).
        if not is_digest(pixels):
            raise ValueError("pixels: neither an image nor its digest")
        return pixels[1]
    if d.get("level", 0) != 0 or not isinstance(pixels, (bytes, bytearray)):
        return None
    h = hashlib.blake2b(digest_size=8)
    h.update(repr((d.get("internalformat"), d.get("width"), d.get("height"), d.get("format"),
                   d.get("type"))).encode())
    h.update(pixels)
    return h.hexdigest()


# Textures whose attached image is one of several (a face, a layer, a
# slice) or all of them (layered rendering).
LAYERED_TARGETS = {"GL_TEXTURE_CUBE_MAP", "GL_TEXTURE_CUBE_MAP_ARRAY", "GL_TEXTURE_2D_ARRAY", "GL_TEXTURE_3D",
                   "GL_TEXTURE_1D_ARRAY", "GL_TEXTURE_2D_MULTISAMPLE_ARRAY"}
# The textargets glFramebufferTexture1D, 2D and 3D take (Mesa 22.3's
# check_textarget); the texture's own target must be the one named (a
# cube map's: one of its faces).
TEXTARGETS = {1: {"GL_TEXTURE_1D", "GL_TEXTURE_1D_ARRAY"},
              2: {"GL_TEXTURE_2D", "GL_TEXTURE_RECTANGLE", "GL_TEXTURE_2D_MULTISAMPLE", "GL_TEXTURE_2D_ARRAY",
                  "GL_TEXTURE_2D_MULTISAMPLE_ARRAY"} | set(CUBE_FACES),
              3: {"GL_TEXTURE_3D"}}


def image_place(key):
    """Which image an attachment key names, as Mesa compares attachments:
    (texture, level, cube map face, layer), a layered one's at face and
    layer 0."""
    level = key[2] if len(key) > 2 and not isinstance(key[2], str) else 0
    spec = key[key.index("layer") + 1] if "layer" in key else None
    if isinstance(spec, str):
        return key[:2], level, CUBE_FACES.index(spec) if spec in CUBE_FACES else 0, 0
    return key[:2], level, 0, spec or 0


class FramebufferCalls:
    """self.s.draw_fbo: the bound draw framebuffer; self.s.fbo_depth[fbo] =
    ("texture" | "renderbuffer", name) of its depth attachment (a deleted
    image that lives on for a framebuffer not bound: ("deleted", name, n)
    in the name's place); the framebuffer and renderbuffer names a core
    profile binds; the sizes of textures' level 0 and renderbuffers; the
    digests of textures' level-0 images; texture units' bindings, and the
    buffers of texture buffer objects."""

    def h_gen_names(self, no, name, a, args):
        """glGenFramebuffers, glCreateFramebuffers, glGenRenderbuffers,
        glCreateRenderbuffers, glGenTextures: names a core profile binds;
        glGenSamplers, glCreateSamplers: the names a bind takes in every
        profile."""
        d = dict(args)
        kind = next((k.lower() for k in ("Renderbuffer", "Sampler", "Texture") if k in name), "framebuffer")
        names = d.get(f"{kind}s")
        if not isinstance(names, list):
            return   # apitrace recorded no names (a negative count: GL_INVALID_VALUE)
        attr = f"{kind}_names"
        if getattr(self.s, attr) is None:
            setattr(self.s, attr, set())
        for n in names:
            n = checked(no, integer, n, f"{name}: a {kind} name", *U32)
            getattr(self.s, attr).add(n)
            if "Create" in name and kind in ("framebuffer", "renderbuffer") and n:
                getattr(self.s, f"{kind}_objects").add(n)   # (made by the call itself)

    def h_bind_framebuffer(self, no, name, a, args):
        d = dict(args)
        target = d["target"]   # (an enumerant, by name where it is one: image_calls)
        fb = checked(no, integer, d["framebuffer"], f"{name}: the framebuffer", *U32)
        if not generated_name(self.core, self.s.framebuffer_names, fb) or target not in (
                "GL_FRAMEBUFFER", "GL_DRAW_FRAMEBUFFER", "GL_READ_FRAMEBUFFER"):
            return   # GL_INVALID_OPERATION or GL_INVALID_ENUM: no binding, no object
        if fb:
            self.s.framebuffer_objects.add(fb)
        before = (self.s.draw_fbo, self.s.read_fbo)
        if target in ("GL_FRAMEBUFFER", "GL_DRAW_FRAMEBUFFER"):
            self.s.draw_fbo = fb
        if target in ("GL_FRAMEBUFFER", "GL_READ_FRAMEBUFFER"):
            self.s.read_fbo = fb
        if (self.s.draw_fbo, self.s.read_fbo) != before:
            self.s.new_buffers = True   # (Mesa's _mesa_bind_framebuffers: a binding that changes)

    def h_framebuffer_texture(self, no, name, a, args, layer=None):
        """glFramebufferTexture(2D), glFramebufferRenderbuffer: an image
        attached to the framebuffer bound at the call's target, the depth
        one (which pass the framebuffer is) and the others (each must have
        an image, of the screen's size or larger, for the framebuffer to be
        the camera pass: camera_pass)."""
        d = dict(args)
        fb = self.s.read_fbo if d.get("target") == "GL_READ_FRAMEBUFFER" else self.s.draw_fbo
        attachment = d.get("attachment")
        if fb and (attachment in DEPTH_ATTACHMENTS or attachment in OTHER_ATTACHMENTS):
            kind = "renderbuffer" if "Renderbuffer" in name else "texture"
            obj = checked(no, integer, d.get("renderbuffer" if kind == "renderbuffer" else "texture"),
                          f"{name}: the {kind}", *U32)
            level = checked(no, integer, d.get("level", 0), f"{name}: the level", -(1 << 31), (1 << 31) - 1) \
                if kind == "texture" else 0
            if level < 0:
                return   # GL_INVALID_VALUE: the attachment stays
            if kind == "renderbuffer":
                if d.get("renderbuffertarget", "GL_RENDERBUFFER") != "GL_RENDERBUFFER" or obj and \
                        obj not in self.s.renderbuffer_objects:
                    return   # GL_INVALID_ENUM or GL_INVALID_OPERATION (no such object): nothing changes
                if attachment == "GL_DEPTH_STENCIL_ATTACHMENT" and obj and self.s.formats.get(
                        ("renderbuffer", obj), "GL_DEPTH_STENCIL") not in DEPTH_STENCIL_FORMATS | {UNCERTAIN,
                                                                                           "GL_RGB9_E5"}:
                    # (Mesa: storage of another format there is
                    # GL_INVALID_OPERATION; none yet, or one llvmpipe gives
                    # no format of its own (shared exponent), is taken)
                    return
                self.decides = True   # (Mesa: _mesa_update_framebuffer_visual, after a call it takes)
            elif obj and self.texture_attachment_refused(name, d, obj, level, layer):
                return
            self.attachments_changed(fb)
            # A texture's level other than 0 has that level's size (or none
            # given: the framebuffer is incomplete and draws nothing there).
            key = None if not obj else (kind, obj) if level == 0 else (kind, obj, level)
            if key and kind == "texture":
                # A layer (glFramebufferTextureLayer's, a 3D slice), a
                # cube map's face, layer 0 of a layered texture named
                # by its target, or all of a layered texture (a point
                # light's shadow, a reflection): named so, another pass
                # than the camera's.
                target = self.s.texture_targets.get(obj)
                if layer is not None:
                    # (a cube map's layer is its face, as Mesa keeps it)
                    key += ("layer", CUBE_FACES[layer] if target == CUBE else layer)
                elif d.get("textarget") in CUBE_FACES:
                    key += ("layer", d["textarget"])
                elif target in LAYERED_TARGETS:
                    key += ("layer", 0 if d.get("textarget") is not None else "all")
                # The depth and stencil attachment points given the same
                # image share one attachment, the first one's (Mesa's
                # reuse_framebuffer_texture_attachment).
                other = self.s.fbo_attachments.get(fb, {}).get("GL_STENCIL_ATTACHMENT") \
                    if attachment == "GL_DEPTH_ATTACHMENT" else \
                    self.s.fbo_depth.get(fb) if attachment == "GL_STENCIL_ATTACHMENT" else None
                if other is not None and image_place(other) == image_place(key):
                    key = other
            if attachment in DEPTH_ATTACHMENTS:
                self.s.fbo_depth[fb] = key
            if attachment != "GL_DEPTH_ATTACHMENT":
                # GL_DEPTH_STENCIL_ATTACHMENT: the image is the stencil
                # attachment too (a depth-only one there leaves the
                # framebuffer incomplete: framebuffer_complete).
                point = "GL_STENCIL_ATTACHMENT" if attachment == "GL_DEPTH_STENCIL_ATTACHMENT" else attachment
                if key is None:
                    self.s.fbo_attachments.get(fb, {}).pop(point, None)
                else:
                    self.s.fbo_attachments.setdefault(fb, {})[point] = key
        tex = d.get("texture")
        if "Texture" in name and fb and isinstance(tex, int) and not isinstance(tex, bool) and tex > 0:
            # Its image is the GPU's from then on (a vertex shader that
            # reads it is refused: the converter runs no fragment shader).
            self.texture_rendered(tex, no, f"{name} attaches it to framebuffer {fb}")

    def texture_attachment_refused(self, name, d, tex, level, layer):
        """Whether GL refuses to attach texture `tex` at `level` (and
        `layer`) (Mesa 22.3 framebuffer_texture, check_textarget,
        check_layer, check_level): no such texture; a textarget the call's
        dimensions do not take, or not the texture's target (a cube map's:
        one of its faces); a layer of a texture that has none, or past the
        cube map's six faces or llvmpipe's 2048 layers; a level past the
        target's last or an immutable texture's levels. The call then
        changes nothing."""
        target = self.s.texture_targets.get(tex)
        if target is None or not generated_name(self.core, self.s.texture_names, tex) \
                or target in ("GL_TEXTURE_BUFFER", "GL_TEXTURE_EXTERNAL_OES"):
            return True   # (no such texture, or one no framebuffer takes)
        textarget = d.get("textarget")
        dims = {"1D": 1, "2D": 2, "3D": 3}.get(base_name(name)[-2:])
        if textarget is not None and (dims is not None and textarget not in TEXTARGETS[dims] or (
                textarget not in CUBE_FACES if target == CUBE else textarget != target)):
            return True
        if layer is not None and (target not in LAYERED_TARGETS or layer >= (
                6 if target == CUBE else MAX_3D_SIZE if target == BOX else MAX_LAYERS)):
            return True
        last = 0 if target in SINGLE_LEVEL else 11 if target == BOX else MAX_LEVEL
        tl = self.s.texture_levels.get(("texture", tex))
        immutable = tl.immutable if tl is not None else None
        return level > last or immutable is not None and level >= immutable

    def h_framebuffer_texture_layer(self, no, name, a, args):
        """glFramebufferTextureLayer: a layer of an array, 3D or cube map
        texture attached, as glFramebufferTexture's image, named with its
        layer (a size the converter knows for no such image: a framebuffer
        it is attached to is another pass than the camera's, as a shadow
        map cascade's is); a negative layer is GL_INVALID_VALUE."""
        d = dict(args)
        layer = checked(no, integer, d.get("layer", 0), f"{name}: the layer", *I32)
        if layer < 0:
            return
        self.h_framebuffer_texture(no, name, a, args, layer=layer)

    def h_framebuffer_texture_3d(self, no, name, a, args):
        """glFramebufferTexture3D: slice `zoffset` of a 3D texture, as
        glFramebufferTextureLayer attaches it."""
        d = dict(args)
        self.h_framebuffer_texture_layer(no, name, a, [(k, v) for k, v in args if k != "zoffset"]
                                         + [("layer", d.get("zoffset", 0))])

    def h_renderbuffer_storage(self, no, name, a, args):
        d = dict(args)
        w, h = d.get("width"), d.get("height")
        if not isinstance(w, int) or not isinstance(h, int):
            fail_call(no, f"{name}: impossible size")
        if not self.s.renderbuffer:
            return   # no renderbuffer bound: GL_INVALID_OPERATION
        fmt = d.get("internalformat")
        if not (0 <= w <= MAX_RENDERBUFFER_SIZE and 0 <= h <= MAX_RENDERBUFFER_SIZE) \
                or not isinstance(fmt, str) or fmt.startswith("GL_COMPRESSED") \
                or isinstance(d.get("samples"), int) and d["samples"] < 0:
            return   # GL_INVALID_VALUE or GL_INVALID_ENUM: the renderbuffer keeps its image
        if not (fmt in self.renderable() or fmt in DEPTH_FORMATS or fmt in DEPTH_STENCIL_FORMATS
                or fmt.startswith("GL_STENCIL_INDEX") or fmt == "GL_RGB9_E5"):
            fmt = UNCERTAIN   # (one Mesa may refuse: the renderbuffer's image is not known)
        rb = ("renderbuffer", self.s.renderbuffer)
        # Samples as asked (glretrace's replay asks at most llvmpipe's 4),
        # and as llvmpipe gives them: 4 for any count from 1.
        asked = min(d["samples"], MAX_SAMPLES) if isinstance(d.get("samples"), int) else 0
        if (self.s.sizes.get(rb), self.s.formats.get(rb), self.s.multisampled.get(rb, 0)) != ((w, h), fmt, asked):
            self.images_changed(lambda key: key[:2] == rb)   # (the same storage again: no new image)
        self.s.new_buffers = True   # (Mesa flags a state update first, either way)
        self.s.sizes[("renderbuffer", self.s.renderbuffer)] = (w, h)
        self.s.formats[("renderbuffer", self.s.renderbuffer)] = fmt
        self.s.multisampled[rb] = MAX_SAMPLES if asked else 0
        self.depths_replaced(("renderbuffer", self.s.renderbuffer), f"are undefined since call {no} gave the "
                                                                    f"renderbuffer storage ({printable(name)})")

    def h_bind_renderbuffer(self, no, name, a, args):
        rb = checked(no, integer, dict(args).get("renderbuffer"), f"{name}: the renderbuffer", *U32)
        if generated_name(self.core, self.s.renderbuffer_names, rb) and \
                dict(args).get("target", "GL_RENDERBUFFER") == "GL_RENDERBUFFER":
            self.s.renderbuffer = rb
            if rb:
                self.s.renderbuffer_objects.add(rb)

    def detach_deleted(self, kind, obj):
        """A texture or renderbuffer deleted: detached from the bound draw
        and read framebuffers, as though glFramebuffer{Texture,Renderbuffer}
        had been called with 0 there (GL 4.5, 9.2.7 and 9.2.8; Mesa 22.3:
        such a framebuffer with no other attachment is incomplete and draws
        nothing). Framebuffers not bound keep the image: it lives on for
        them, its size moved to a name no call can give (GL 4.5, 5.1.3),
        and the name with its sizes is free for a new object."""
        bound = {self.s.draw_fbo, self.s.read_fbo} - {0}
        holders = []
        for fb, att in self.s.fbo_depth.items():
            if att is not None and att[0] == kind and att[1] == obj:
                if fb in bound:
                    self.s.fbo_depth[fb] = None
                    self.attachments_changed(fb)
                else:
                    holders.append(fb)
        others = []   # (framebuffer, attachment point) of the other images
        for fb, atts in self.s.fbo_attachments.items():
            for point, att in list(atts.items()):
                if att[0] == kind and att[1] == obj:
                    if fb in bound:
                        del atts[point]
                        self.attachments_changed(fb)
                    else:
                        others.append((fb, point))
        keys = [k for k in self.s.sizes if k[0] == kind and k[1] == obj]
        if holders or others:
            self.s.deleted_images += 1
            kept = ("deleted", obj, self.s.deleted_images)
            for k in keys:
                self.s.sizes[(kind, kept) + k[2:]] = self.s.sizes[k]
                for kept_by in (self.s.multisampled, self.s.formats, self.s.depth_types):
                    if k in kept_by:
                        kept_by[(kind, kept) + k[2:]] = kept_by[k]
            for fb in holders:
                self.s.fbo_depth[fb] = (kind, kept) + self.s.fbo_depth[fb][2:]
            for fb, point in others:
                self.s.fbo_attachments[fb][point] = (kind, kept) + self.s.fbo_attachments[fb][point][2:]
            self.depths_renamed((kind, obj), (kind, kept))
            if (kind, obj) in self.s.texture_levels:
                self.s.texture_levels[(kind, kept)] = self.s.texture_levels[(kind, obj)]
        self.s.texture_levels.pop((kind, obj), None)
        for k in keys:
            del self.s.sizes[k]
        for kept_by in (self.s.multisampled, self.s.formats, self.s.depth_types):
            for k in [k for k in kept_by if k[:2] == (kind, obj)]:
                del kept_by[k]

    def h_delete_renderbuffers(self, no, name, a, args):
        for rb in dict(args).get("renderbuffers") or []:
            if isinstance(rb, int) and not isinstance(rb, bool) and rb > 0:
                if self.s.renderbuffer_names is not None:
                    self.s.renderbuffer_names.discard(rb)
                self.s.renderbuffer_objects.discard(rb)
                if self.s.renderbuffer == rb:
                    self.s.renderbuffer = 0   # GL binds renderbuffer 0
                self.detach_deleted("renderbuffer", rb)

    def h_delete_textures(self, no, name, a, args):
        """glDeleteTextures: a texture bound to a unit is unbound there (the
        unit's target reads texture 0: a buffer texture's texelFetch
        then reads zeros, as in Mesa), detached from the bound
        framebuffers (detach_deleted); its name is free for a new texture,
        with no target, size, image or buffer."""
        for tex in dict(args).get("textures") or []:
            if isinstance(tex, int) and not isinstance(tex, bool) and tex > 0:
                for key, v in self.s.units.items():
                    if v == tex:
                        self.s.units[key] = 0
                if self.s.texture == tex:
                    self.s.texture = 0
                for unit in [u for u, b in self.s.image_units.items() if b[0] == tex]:
                    del self.s.image_units[unit]   # unbound from its image units too
                    self.s.image_writes.discard(unit)
                if self.s.texture_names is not None:
                    self.s.texture_names.discard(tex)
                self.detach_deleted("texture", tex)
                self.s.texture_targets.pop(tex, None)
                self.s.texture_images.pop(tex, None)
                self.s.texture_buffers.pop(tex, None)
                self.forget_texture_calls(tex)

    def h_tex_image(self, no, name, a, args):
        """The size of a texture's level 0 (a framebuffer attachment's size)
        and the digest of its image (what rules name it by)."""
        d = dict(args)
        if base_name(name) in ("glTexImage2D", "glTexStorage2D", "glCompressedTexImage2D"):
            self.keep_texture_call(no, base_name(name), d)
            if refused_storage(d) if base_name(name) == "glTexStorage2D" else refused_level(base_name(name), d):
                return   # GL certainly refuses it: the texture keeps its size
        if not self.record_levels(no, base_name(name), d):
            return   # GL_INVALID_OPERATION on an immutable texture (or refused): its storage stays
        w, h = d.get("width"), d.get("height", 1)
        level = d.get("level", 0)
        self.depth_image_written(no, name, d)
        self.texture_levels_changed(d)
        if level == 0 and isinstance(w, int) and isinstance(h, int):
            tex = self.bound_texture(d.get("target"))
            self.s.sizes[("texture", tex)] = (w, h)
            self.s.multisampled[("texture", tex)] = MAX_SAMPLES if "Multisample" in name else 0
            self.s.formats[("texture", tex)] = d.get("internalformat")
            self.s.depth_types[("texture", tex)] = d.get("type")   # (an unsized depth format's bits)
            self.s.texture_images[tex] = texture_image_digest(d)
            levels = d.get("levels")
            if isinstance(levels, int) and not isinstance(levels, bool):   # glTexStorage2D: the levels below
                for i in range(1, min(levels, 32)):
                    self.s.sizes[("texture", tex, i)] = (max(1, w >> i), max(1, h >> i))
        elif isinstance(level, int) and isinstance(w, int) and isinstance(h, int):
            tex = self.bound_texture(d.get("target"))
            self.s.sizes[("texture", tex, level)] = (w, h)   # a framebuffer attachment of that level

    def h_tex_sub_image(self, no, name, a, args):
        """glTexSubImage2D and glCompressedTexSubImage2D of a whole level 0 (the
        usual upload after glTexStorage2D): the texture's image is the one
        given, and rules name it by its digest (of the call's own size,
        format, type and pixels); a part of a level leaves the digest of the
        last whole upload."""
        d = dict(args)
        self.keep_texture_call(no, base_name(name), d)
        self.depth_image_written(no, name, d)
        tex = self.bound_texture(d.get("target"))
        if d.get("level", 0) == 0 and d.get("xoffset") == 0 and d.get("yoffset") == 0 and \
                self.s.sizes.get(("texture", tex)) == (d.get("width"), d.get("height")):
            self.s.texture_images[tex] = texture_image_digest(d)

    def depth_image_written(self, no, name, d):
        """A texture level given storage or pixels: as a camera-pass depth
        buffer, contents the converter does not follow."""
        level, levels = d.get("level", 0), d.get("levels")   # glTexStorage2D: levels from 0
        if not self.active or not isinstance(level, int) or isinstance(level, bool):
            return
        tex = self.bound_texture(d.get("target"))
        if isinstance(levels, int) and not isinstance(levels, bool):
            written = range(min(levels, 32))
        else:
            written = (level,)
        for lv in written:
            self.depths_replaced(("texture", tex) if lv == 0 else ("texture", tex, lv),
                                 f"are undefined since call {no} gave the texture an image ({printable(name)})")

    def h_active_texture(self, no, name, a, args):
        """glActiveTexture: GL_TEXTUREi, or past GL_TEXTURE31 the number
        apitrace writes (or another enumerant's name of that number); a unit
        past llvmpipe's 192 (GL_MAX_COMBINED_TEXTURE_IMAGE_UNITS) is
        GL_INVALID_ENUM and changes nothing."""
        unit = a[0] if a else None
        if isinstance(unit, str) and unit.startswith("GL_TEXTURE") and unit[10:].isdigit():
            unit = int(unit[10:])
        elif isinstance(unit, int) and not isinstance(unit, bool):
            unit -= GL_TEXTURE0
        elif isinstance(unit, str) and unit.startswith("GL_"):
            return   # another enumerant: GL_INVALID_ENUM
        else:
            fail_call(no, f"{name}: {printable(unit)} is not a texture unit")
        if 0 <= unit < MAX_TEXTURE_UNITS:
            self.s.active_unit = unit

    def h_bind_texture(self, no, name, a, args):
        d = dict(args)
        target = d["target"]   # (an enumerant, by name where it is one: image_calls)
        tex = checked(no, integer, d["texture"], f"{name}: the texture", *U32)
        if target not in TEXTURE_TARGETS or (target in DESKTOP_BIND_TARGETS if self.es else
                                                   target == "GL_TEXTURE_EXTERNAL_OES"):
            return   # GL_INVALID_ENUM: nothing is bound
        if tex and (self.s.texture_targets.get(tex, target) != target
                    or not generated_name(self.core, self.s.texture_names, tex)):
            return   # another target's texture, or (core) a name glGenTextures did not give: GL_INVALID_OPERATION
        self.s.units[(self.s.active_unit, target)] = tex
        if tex:
            self.s.texture_targets.setdefault(tex, target)
        if target == "GL_TEXTURE_2D":
            self.s.texture = tex   # what selection rules name as a draw's texture

    def h_bind_texture_unit(self, no, name, a, args):
        """glBindTextureUnit(unit, texture) and glBindTextures(first, count,
        textures): each texture bound to its unit at the target it was
        first bound to (0 unbinds every target of the unit). GL 4.5, 8.1:
        units past llvmpipe's 192 make the whole call do nothing; an entry
        that names no texture (never bound nor created, or deleted) is
        skipped, the others bound."""
        d = dict(args)
        if "Unit" in name:
            pairs = [(d.get("unit"), d.get("texture"))]
        else:
            first, count, texs = d.get("first"), d.get("count"), d.get("textures")
            first = checked(no, integer, first, f"{name}: first", *U32)
            count = checked(no, integer, count, f"{name}: count", *I32)
            if count < 0:
                return   # GL_INVALID_VALUE: nothing is bound
            if texs is None or texs == 0 and not isinstance(texs, bool):   # NULL (apitrace records it as 0)
                texs = [0] * count
            if not isinstance(texs, list) or len(texs) < count:
                fail_call(no, f"{name}: fewer textures than its count")
            pairs = [(first + i, t) for i, t in enumerate(texs[:count])]
        if any(not isinstance(u, int) or isinstance(u, bool) or u >= MAX_TEXTURE_UNITS for u, _ in pairs):
            return   # GL_INVALID_OPERATION (GL_INVALID_VALUE for glBindTextureUnit): nothing is bound
        for unit, tex in pairs:
            unit = checked(no, integer, unit, f"{name}: the unit", *U32)
            tex = checked(no, integer, tex, f"{name}: the texture", *U32)
            if tex == 0:
                for key in [k for k in self.s.units if k[0] == unit]:
                    self.s.units[key] = 0
                continue
            target = self.s.texture_targets.get(tex)
            if target is None or not generated_name(self.core, self.s.texture_names, tex):
                continue   # no such texture: GL_INVALID_OPERATION, this unit keeps its binding
            self.s.units[(unit, target)] = tex
            if unit == self.s.active_unit and target == "GL_TEXTURE_2D":
                self.s.texture = tex

    def h_tex_buffer(self, no, name, a, args):
        from .textures import DEFAULT_BUFFER_TEXTURE
        d = dict(args)
        if d.get("target") != "GL_TEXTURE_BUFFER":
            return   # GL_INVALID_ENUM: the call changes nothing
        tex = self.bound_texture("GL_TEXTURE_BUFFER") or DEFAULT_BUFFER_TEXTURE   # (none bound: the default one)
        buf, fmt = d.get("buffer"), d.get("internalformat")
        if not isinstance(buf, int) or isinstance(buf, bool) or buf < 0:
            fail_call(no, f"{name}: an impossible buffer")
        buf = checked(no, integer, buf, f"{name}: the buffer", *U32)
        offset, size = d.get("offset", 0), d.get("size")
        if name == "glTexBufferRange":
            offset = checked(no, integer, offset, f"{name}: the offset", *I64)
            size = checked(no, integer, size, f"{name}: the size", *I64)
        if not isinstance(fmt, str) or fmt not in TEXTURE_BUFFER_FORMATS and (self.core or fmt not in
                                                                      LEGACY_TEXTURE_BUFFER_FORMATS):
            return   # GL_INVALID_ENUM: the call changes nothing
        # Mesa's GL_INVALID_VALUE and GL_INVALID_OPERATION (GL 4.5, 8.1):
        # a range of a buffer at a negative offset or one not a multiple of
        # 16 (GL_TEXTURE_BUFFER_OFFSET_ALIGNMENT in llvmpipe), of no bytes,
        # or past the buffer's size as it is now; a name that is no buffer.
        # The texture keeps what it had.
        if size is not None and buf and (offset < 0 or offset % 16 or size <= 0
                                         or offset + size > len(self.s.buffers.get(buf, b""))):
            return
        if not self.generated(buf):
            return
        self.s.texture_buffers[tex] = (fmt, buf, offset, size)

    def h_delete_framebuffers(self, no, name, a, args):
        for fb in dict(args).get("framebuffers") or []:
            if isinstance(fb, int) and not isinstance(fb, bool) and fb > 0:
                if self.s.framebuffer_names is not None:
                    self.s.framebuffer_names.discard(fb)
                self.s.framebuffer_objects.discard(fb)
                self.s.fbo_depth.pop(fb, None)
                self.s.fbo_attachments.pop(fb, None)
                self.s.fbo_draw_buffers.pop(fb, None)
                self.s.fbo_one_output.pop(fb, None)
                self.s.fbo_status.pop(fb, None)
                self.s.fbo_integer.pop(fb, None)
                self.s.fbo_buffer_names.pop(fb, None)
                if fb in (self.s.draw_fbo, self.s.read_fbo):
                    self.s.new_buffers = True
                if self.s.draw_fbo == fb:
                    self.s.draw_fbo = 0   # GL binds the window's framebuffer again
                if self.s.read_fbo == fb:
                    self.s.read_fbo = 0

    def h_blit_framebuffer(self, no, name, a, args):
        """glBlitFramebuffer, glBlitNamedFramebuffer. Only a depth copy into
        the camera pass's framebuffer can change the unit's input: a copy of
        the whole of one camera-pass depth buffer into another (an MSAA
        resolve, a deferred renderer's depth handed to its forward pass)
        gives the destination the source's contents (CameraDepthCalls); a
        copy of a part of it (a rectangle, or under the scissor), moved or
        scaled, or from another pass gives it contents the converter does
        not follow, and a draw that tests depth against them is refused. A
        colour or stencil copy, one into another pass's framebuffer, and
        one GL refuses (a bit no buffer has: GL_INVALID_VALUE; depth with
        another filter than GL_NEAREST, depth formats that differ, a name
        that is no framebuffer: GL_INVALID_OPERATION or GL_INVALID_ENUM)
        change nothing."""
        d = dict(args)
        self.gpu_wrote()
        # Mesa tests both framebuffers' completeness first, whatever follows
        # (blit_framebuffer's _mesa_update_framebuffer); a name that is no
        # framebuffer is GL_INVALID_OPERATION before it.
        if "drawFramebuffer" in d:
            pair = [checked(no, integer, d[k], f"{name}: the {what} framebuffer", *U32)
                    for k, what in (("readFramebuffer", "read"), ("drawFramebuffer", "draw"))]
            if all(not fb or self.known_framebuffer(fb) for fb in pair):
                self.test_framebuffers(no, name, pair)
        else:
            self.test_framebuffers(no, name, (self.s.read_fbo, self.s.draw_fbo))
        bits = {0x100: "GL_DEPTH_BUFFER_BIT", 0x400: "GL_STENCIL_BUFFER_BIT", 0x4000: "GL_COLOR_BUFFER_BIT"}
        mask, unknown = bitfield(d.get("mask", 0), no, f"{name}: the mask", bits)
        if "GL_DEPTH_BUFFER_BIT" not in mask:
            return
        refused = unknown or not mask <= set(bits.values())   # GL_INVALID_VALUE
        if "drawFramebuffer" in d:
            src = checked(no, integer, d["readFramebuffer"], f"{name}: the read framebuffer", *U32)
            dst = checked(no, integer, d["drawFramebuffer"], f"{name}: the draw framebuffer", *U32)
        else:
            src, dst = self.s.read_fbo, self.s.draw_fbo
        rect = [checked(no, integer, d.get(k), f"{name}: {k}", *I32)
                for k in ("srcX0", "srcY0", "srcX1", "srcY1", "dstX0", "dstY0", "dstX1", "dstY1")]
        if not self.active or not self.camera_pass(dst):
            return
        if src and isinstance(self.s.fbo_status.get(src), str):
            fail_call(no, f"{printable(name)}: whether it copies depth into the camera pass depends on read "
                          f"framebuffer {src}'s completeness, which the converter does not compute "
                          f"({self.s.fbo_status[src]}; docs/gl-capture.md)")
        if src and self.s.fbo_status.get(src) is False:
            return   # GL_INVALID_FRAMEBUFFER_OPERATION: an incomplete read framebuffer copies nothing
        if src and self.s.fbo_depth.get(src) is None:
            # A read framebuffer with no depth buffer copies no depth (GL
            # ignores the bit), and one with no attachment is incomplete
            # (GL_INVALID_FRAMEBUFFER_OPERATION): nothing changes.
            return
        refused = refused or "drawFramebuffer" in d and any(
            fb and not self.known_framebuffer(fb) for fb in (src, dst))   # no such framebuffer
        if refused or d.get("filter") not in ("GL_NEAREST", 0x2600) or self.depth_class(src) != self.depth_class(dst):
            return
        if self.depth_key(src) == self.depth_key(dst):
            return   # one buffer: a copy onto itself changes nothing where it does not overlap (GL refuses that)
        if src and self.s.multisampled.get(self.s.fbo_depth[src][:2]):
            self.depths_replaced(self.depth_key(dst), f"were last written by call {no} ({printable(name)}: a "
                                 "resolve of a multisampled depth buffer, one sample a pixel, which the converter "
                                 "does not follow)")
            return
        if self.camera_pass(src) and rect[:4] == rect[4:]:
            w, h = self.screen
            whole = min(rect[0], rect[2]) <= 0 and min(rect[1], rect[3]) <= 0 \
                and max(rect[0], rect[2]) >= w and max(rect[1], rect[3]) >= h
            if whole and self.covers_screen(self.scissor_rect()):
                self.depths_copied(src, dst)
                return
            how = f"a copy of {'a rectangle' if not whole else 'the part under the scissor'} of another's"
        else:
            how = f"a copy {'moved or scaled' if self.camera_pass(src) else 'from another pass'}"
        self.depths_replaced(self.depth_key(dst), f"were last written by call {no} ({printable(name)}: {how}, "
                                                  "which the converter does not follow)")

    # ---- completeness as Mesa 22.3 keeps it (docs/gl-capture.md, "When it
    # is decided"): a framebuffer object's status, cleared by a change to
    # its attachments or their images, is tested again by a status check
    # or, for a bound one, by the next state update after a change flagged
    # _NEW_BUFFERS; each test has Mesa decide again whether draws are valid.
    def attachments_changed(self, fb):
        """An attachment of framebuffer object fb set, changed or removed
        (Mesa: invalidate_framebuffer, and _NEW_BUFFERS)."""
        self.s.fbo_status.pop(fb, None)
        self.s.new_buffers = True

    def images_changed(self, attached):
        """An image given new storage: every framebuffer object with an
        attachment (a key of fbo_depth or fbo_attachments) `attached`
        accepts is tested again (Mesa: invalidate_rb, check_rtt_cb), and a
        state update is flagged (for a texture only when one is bound)."""
        holders = {fb for fb, key in self.s.fbo_depth.items() if key is not None and attached(key)}
        holders.update(fb for fb, atts in self.s.fbo_attachments.items() for key in atts.values() if attached(key))
        for fb in holders:
            self.s.fbo_status.pop(fb, None)
        return holders

    def texture_levels_changed(self, d):
        """glTexImage2D, glTexStorage2D and their kin: the level they give
        an image (a storage call: every level), wherever attached."""
        levels, level = d.get("levels"), d.get("level", 0)
        if isinstance(levels, int) and not isinstance(levels, bool):
            given = range(32)   # (storage: Mesa looks at every level's attachments)
        elif isinstance(level, int) and not isinstance(level, bool):
            given = (level,)
        else:
            return
        target = face = d.get("target")
        if face in CUBE_FACES:
            target = "GL_TEXTURE_CUBE_MAP"   # (a face of the cube map bound there)
        tex = ("texture", self.bound_texture(target))

        def attached(key):
            # That level; of a cube map, that face (attached alone, as a
            # layer, or with the others: "all").
            if key[:2] != tex or (key[2] if len(key) > 2 and isinstance(key[2], int) else 0) not in given:
                return False
            if face not in CUBE_FACES or "layer" not in key:
                return True
            # (a layered attachment is face 0's, as Mesa keeps it)
            layer = key[key.index("layer") + 1]
            return layer == face or layer == CUBE_FACES.index(face) or layer == "all" and face == CUBE_FACES[0]
        holders = self.images_changed(attached)
        if holders & {self.s.draw_fbo, self.s.read_fbo}:
            self.s.new_buffers = True

    def renderable(self):
        """The colour formats the converter knows llvmpipe renders in this
        context's API."""
        return RENDERABLE if self.es else DESKTOP_RENDERABLE

    def framebuffer_complete(self, fb):
        """Framebuffer object fb's completeness as Mesa 22.3 tests it
        (_mesa_test_framebuffer_completeness, llvmpipe's own test), where
        the converter follows what decides it: True, False, or why it does
        not (a str). Incomplete: no attachment; an image GL never gave (a
        texture level or face, a renderbuffer's storage), one of no pixels,
        a layer past the texture's, a layered cube map whose faces differ,
        a level past 0 of a mutable texture not mipmap complete
        (texture_levels.attached_image); a depth format on a colour
        attachment or another on the depth one; a stencil attachment
        without stencil bits; a compressed or shared-exponent format;
        samples or fixed sample locations that differ; layered and
        unlayered images, or layered images of different targets; separate
        depth and stencil images (llvmpipe: unsupported). Not computed:
        images the converter cannot tell GL gave, textures whose levels it
        does not follow, colour formats outside renderable()."""
        depth = self.s.fbo_depth.get(fb)
        keys = ([("GL_DEPTH_ATTACHMENT", depth)] if depth is not None else []) + \
            list(self.s.fbo_attachments.get(fb, {}).items())
        if not keys:
            return False
        unknown = None
        samples, layering = set(), set()
        for point, key in keys:
            if key[0] == "renderbuffer":
                size = self.s.sizes.get(key)
                if size is None or min(size) <= 0:
                    return False   # (no storage given, or none of pixels)
                if self.s.formats.get(key[:2]) == UNCERTAIN:
                    unknown = unknown or "a renderbuffer's storage the converter cannot tell GL gave"
                    continue
                image = size + (1, self.s.formats.get(key[:2]), self.s.multisampled.get(key, 0), True)
                layered = None
            else:
                image = self.attached_image(key)
                if image is False:
                    return False
                if isinstance(image, str):
                    unknown = unknown or image
                    continue
                layered = self.s.texture_levels[key[:2]].target if key[-1] == "all" else None
            fmt = image[3]
            if isinstance(fmt, str):
                if fmt.startswith("GL_COMPRESSED") or fmt == "GL_RGB9_E5":
                    return False
                depthy = fmt in DEPTH_FORMATS or fmt in DEPTH_STENCIL_FORMATS
                if point == "GL_STENCIL_ATTACHMENT":
                    if fmt not in DEPTH_STENCIL_FORMATS and not fmt.startswith("GL_STENCIL_INDEX"):
                        return False
                elif (point == "GL_DEPTH_ATTACHMENT") != depthy:
                    return False
            samples.add(image[4:6])
            layering.add(layered)
            if point.startswith("GL_COLOR") and fmt not in self.renderable():
                unknown = unknown or f"format {printable(fmt, 40)} attached"
        if len(samples) > 1 or len(layering) > 1:
            return False   # (Mesa: incomplete multisample, incomplete layer targets)
        stencil = self.s.fbo_attachments.get(fb, {}).get("GL_STENCIL_ATTACHMENT")
        if stencil is not None and depth is not None and stencil != depth:
            return False
        return unknown or True

    def named_clear(self, no, name, d):
        """glClearNamedFramebuffer*: Mesa 22.3 binds the named framebuffer
        for drawing (a change decides, and flags a state update), clears
        (its state update tests the named and the read framebuffer), and
        binds the one before again (which decides and flags again)."""
        fb = checked(no, integer, d.get("framebuffer"), f"{name}: the framebuffer", *U32)
        if fb and not self.known_framebuffer(fb):
            return   # GL_INVALID_OPERATION
        bound = self.s.draw_fbo
        if fb != bound:
            self.s.draw_fbo = fb
            self.revalidate()
            self.s.new_buffers = True
        if self.s.new_buffers:
            self.update_framebuffers(no, name)
        if fb != bound:
            self.s.draw_fbo = bound
            self.revalidate()
            self.s.new_buffers = True

    def update_framebuffers(self, no, name):
        """Mesa's state update at a draw, a clear, a pixel read or copy
        with _NEW_BUFFERS pending: the bound draw and read framebuffer
        objects are tested (test_framebuffers), before the call is
        validated."""
        self.s.new_buffers = False
        self.test_framebuffers(no, name, (self.s.draw_fbo, self.s.read_fbo))

    def test_framebuffers(self, no, name, fbs, answer=None):
        """Framebuffer objects among `fbs` whose status is not complete
        tested (Mesa's update_framebuffer, or a status check whose
        `answer` the capture holds: True complete, False not); a test has
        Mesa decide again whether draws are valid. An incomplete one is
        found incomplete again; an untested one is given the capture's
        answer or the converter's (framebuffer_complete). Where the
        converter could not compute the status, whether Mesa tests is not
        known: unless its decision would not change, the call is refused."""
        decide, unknown = False, []
        for fb in dict.fromkeys(fbs):
            if not fb:
                continue
            status = self.s.fbo_status.get(fb, UNTESTED)
            if status is UNTESTED:
                self.s.fbo_status[fb] = self.framebuffer_complete(fb) if answer is None else answer
                self.s.fbo_answered.discard(fb) if answer is None else self.s.fbo_answered.add(fb)
                self.s.fbo_integer[fb] = self.integer_attachment(fb)
                decide = True
            elif answer is not None:
                # The capture's answer says which status Mesa had: a
                # complete one is not tested, an incomplete one is.
                self.s.fbo_status[fb] = answer
                self.s.fbo_answered.add(fb)
                if not answer:
                    self.s.fbo_integer[fb] = self.integer_attachment(fb)
                decide = decide or not answer
            elif isinstance(status, str):
                unknown.append((fb, status))
            elif status is False:
                # Mesa tests an incomplete one again: images its
                # attachments do not name (levels of the mipmap chain, the
                # faces of a layered cube map's base) may have completed it.
                # An answer the capture gave stands until the framebuffer
                # changes.
                if fb not in self.s.fbo_answered:
                    self.s.fbo_status[fb] = self.framebuffer_complete(fb)
                self.s.fbo_integer[fb] = self.integer_attachment(fb)
                decide = True
        if decide:
            self.revalidate()
        elif unknown:
            # Mesa tests only if it found the framebuffer incomplete: its
            # decision then, tried, must be the one it holds.
            before, pipe = self.s.render_fault, self.current_pipeline()
            validated = pipe.validated if pipe is not None else None
            self.revalidate()
            if self.s.render_fault != before:
                fb, why = unknown[0]
                fail_call(no, f"{printable(name)}: whether Mesa decides again here if draws are valid depends on "
                              f"framebuffer {fb}'s completeness, which the converter does not compute ({why}; "
                              "docs/gl-capture.md)")
            if pipe is not None:
                pipe.validated = validated

    def integer_attachment(self, fb):
        """Framebuffer object fb's colour attachment of an integer format,
        as its test finds it complete (Mesa's _IntegerBuffers, which a
        compatibility profile's draws read: integer_buffers_invalid):
        (point, format), None, or why the converter does not know (a str).
        A texture's image gives its format whether or not the converter
        follows the texture's other rules; one it cannot tell GL gave, the
        format its call asked (the framebuffer complete, an image is there)."""
        if self.core or self.es or self.s.fbo_status.get(fb) is not True:
            return None
        unknown = None
        for point, key in sorted(self.s.fbo_attachments.get(fb, {}).items()):
            if not point.startswith("GL_COLOR_ATTACHMENT"):
                continue
            if key[0] == "renderbuffer":
                fmt = self.s.formats.get(key[:2])
            else:
                img, level, face, _ = image_place(key)
                tl = self.s.texture_levels.get(img)
                image = tl.images.get((level, face)) if tl is not None else None
                if self.s.images_passed_over is not None:
                    fmt = UNCERTAIN   # (a call passed over may have given any image)
                elif isinstance(image, tuple):
                    fmt = image[3]
                else:
                    fmt = self.s.formats.get(key[:2], UNCERTAIN) if level == 0 else UNCERTAIN
            if fmt in INTEGER_FORMATS:
                return point, fmt
            if fmt == UNCERTAIN:
                unknown = unknown or f"the format of {point}'s image"
        return unknown

    def depth_class(self, fb):
        """A framebuffer's depth format as glBlitFramebuffer compares them:
        bits and float or not (the window's: 24 bits)."""
        att = self.s.fbo_depth.get(fb) if fb else None
        fmt = self.s.formats.get(att[:2]) if att else "GL_DEPTH_COMPONENT24"
        fmt = str(fmt)
        if "32F" in fmt:
            return "32F"
        for bits in ("16", "32"):
            if f"COMPONENT{bits}" in fmt:
                return bits
        return "24"

    def on_main_drawable(self):
        """Whether the window-system framebuffer now bound is the main
        window's: the drawable current at the capture's first draw into a
        window (a second window or surface is another target, as a
        framebuffer object of another size is: its draws and clears left
        out, its swaps ending no frame). Before that first draw, any."""
        if self.current_drawable in self.pbuffers:
            return False
        return self.main_drawable is None or self.current_drawable == self.main_drawable

    def attachment_size(self, key, status):
        """The (width, height) an attachment `key` draws into, for the
        camera-pass test: None for no image, and for a layer, a face or a
        layered texture (another pass, whatever its size); why it is not
        known (a str). A framebuffer Mesa found complete (`status`: the
        capture's answer) has an image there: one the converter cannot
        tell GL gave is taken at the size its call asked."""
        if key[0] == "renderbuffer":
            return self.s.sizes.get(key)
        if "layer" in key:
            return None
        size = self.plane_size(key)
        if isinstance(size, str) and status is True:
            return self.s.sizes.get(key, size)
        return size

    def camera_pass(self, fb=None):
        """Whether a draw now writes the frame's camera pass (or would,
        into framebuffer `fb`): a complete framebuffer object whose depth
        buffer has the screen's size and whose other attachments each have
        an image at least as large (else GL draws into the smaller area
        they share). Where what decides it is not known, the call is
        refused in one line."""
        fb = self.s.draw_fbo if fb is None else fb
        if not fb:
            return self.on_main_drawable()
        if self.screen is None:
            self.write_header()   # the screen, from the window or the viewport (or the capture's error)
        depth = self.s.fbo_depth.get(fb)
        if depth is None:
            return False
        status = self.s.fbo_status.get(fb, UNTESTED)
        if status is UNTESTED:
            status = self.framebuffer_complete(fb)
        if status is False:
            return False   # (Mesa draws, clears and copies nothing into an incomplete one)
        w, h = self.screen
        keys = [depth] + list(self.s.fbo_attachments.get(fb, {}).values())
        sizes = [self.attachment_size(key, status) for key in keys]
        if not isinstance(sizes[0], str) and sizes[0] != (w, h) or any(
                size is None or not isinstance(size, str) and (size[0] < w or size[1] < h) for size in sizes):
            return False
        unknown = next(((key, size) for key, size in zip(keys, sizes) if isinstance(size, str)), None)
        if unknown is not None:
            key, why = unknown
            tex = f"{key[1][1]} (deleted)" if isinstance(key[1], tuple) else key[1]
            fail_call(self.last_call, f"{printable(self.last_name or 'the call')}: whether it writes framebuffer "
                                      f"{fb} depends on the size of its attachment of texture {tex}, "
                                      f"which the converter does not know ({why}; docs/gl-capture.md)")
        if isinstance(status, str):
            fail_call(self.last_call, f"{printable(self.last_name or 'the call')}: whether it writes framebuffer "
                                      f"{fb}, of the camera pass's size, depends on the framebuffer's completeness, "
                                      f"which the converter does not compute ({status}; docs/gl-capture.md)")
        return True

    HANDLERS = {
        "glBindFramebuffer": h_bind_framebuffer,
        "glDeleteFramebuffers": h_delete_framebuffers,
        "glBlitFramebuffer": h_blit_framebuffer,
        "glBlitNamedFramebuffer": h_blit_framebuffer,
        "glFramebufferTexture1D": h_framebuffer_texture,
        "glFramebufferTexture2D": h_framebuffer_texture,
        "glFramebufferTexture3D": h_framebuffer_texture_3d,
        "glFramebufferTextureLayer": h_framebuffer_texture_layer,
        "glFramebufferTexture": h_framebuffer_texture,
        "glFramebufferRenderbuffer": h_framebuffer_texture,
        "glGenFramebuffers": h_gen_names,
        "glCreateFramebuffers": h_gen_names,
        "glGenRenderbuffers": h_gen_names,
        "glCreateRenderbuffers": h_gen_names,
        "glDeleteRenderbuffers": h_delete_renderbuffers,
        "glDeleteTextures": h_delete_textures,
        "glBindRenderbuffer": h_bind_renderbuffer,
        "glRenderbufferStorage": h_renderbuffer_storage,
        "glRenderbufferStorageMultisample": h_renderbuffer_storage,
        "glTexImage2D": h_tex_image,
        "glTexStorage2D": h_tex_image,
        "glCompressedTexImage2D": h_tex_image,
        "glTexSubImage2D": h_tex_sub_image,
        "glCompressedTexSubImage2D": h_tex_sub_image,
        "glTexImage2DMultisample": h_tex_image,
        "glTexStorage2DMultisample": h_tex_image,
        "glActiveTexture": h_active_texture,
        "glBindTexture": h_bind_texture,
        "glBindTextureUnit": h_bind_texture_unit,
        "glBindTextures": h_bind_texture_unit,
        "glTexBuffer": h_tex_buffer,
        "glTexBufferRange": h_tex_buffer,
    }

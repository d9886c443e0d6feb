"""Direct state access (GL 4.5) on textures, framebuffers and renderbuffers:
each call is its bind-to-edit form on the object it names, run through that
form's handler with the object bound for the call alone (buffers and vertex
arrays have theirs in buffers.py and attributes.py).

A texture call names a texture that exists, with its target: one made by
glCreateTextures, or bound once; another name is GL_INVALID_OPERATION and
the call does nothing, as in Mesa. An EXT_direct_state_access form names
the target too: a name not yet a texture becomes one of that target, 0 is
the target's default texture, and a texture of another target is
GL_INVALID_OPERATION (ext_texture). A
framebuffer or renderbuffer call on a name that is no object (bound once,
or made by glCreate*) does nothing either, in every profile."""
from ...cli import I32, U32, integer
from ..errors import checked, fail_call
from ..gl_tables import base_name
from .framebuffers import FramebufferCalls
from .per_fragment import PerFragmentCalls
from .textures import TextureImageCalls
from .image_calls import TEXTURE_TARGETS
from .texture_levels import CUBE, CUBE_FACES, TextureLevelCalls

MAX_CREATED = 1 << 16   # names one glCreate* call makes (a larger n is the capture's error)


def on_texture(handler, as_name, target=None):
    """The handler of `as_name` (the bind-to-edit form) run with the named
    texture bound on the active unit at its target (`target`: only a
    texture of that target, as for glTextureBuffer)."""
    def h(self, no, name, a, args):
        d = dict(args)
        tex = checked(no, integer, d.get("texture"), f"{name}: the texture", *U32)
        if name.endswith("EXT"):
            bound_target = ext_texture(self, tex, d.get("target"))
        else:
            bound_target = self.s.texture_targets.get(tex)
        if bound_target is None or not tex and not name.endswith("EXT") \
                or target is not None and bound_target != target:
            return   # GL_INVALID_OPERATION: no such texture (or not of the call's target)
        run_bound(self, tex, bound_target, handler, no, as_name,
                  [("target", bound_target)] + [(k, v) for k, v in args if k not in ("texture", "target")])
    return h


def ext_texture(self, tex, target, faces=False):
    """The target of texture `tex` as an EXT_direct_state_access call
    naming it with `target` finds it (Mesa's _mesa_lookup_or_create_texture):
    0 is the target's default texture, the one glBindTexture(target, 0)
    binds; a name not yet a texture becomes one of that target; a texture
    of another target, or no texture target, is None (GL_INVALID_OPERATION
    or GL_INVALID_ENUM: the call does nothing). A cube map's face names the
    cube map for an image call (`faces`); for any other it is
    GL_INVALID_ENUM."""
    bound = CUBE if faces and target in CUBE_FACES else target
    if bound not in TEXTURE_TARGETS or tex and self.s.texture_targets.setdefault(tex, bound) != bound:
        return None
    return bound


def run_bound(self, tex, target, handler, no, name, args):
    """handler(name, args) run with texture tex bound on the active unit at
    `target` for the call alone."""
    key = (self.s.active_unit, target)
    saved = self.s.units.get(key)
    self.s.units[key] = tex
    try:
        handler(self, no, name, [v for _, v in args], args)
    finally:
        if saved is None:
            del self.s.units[key]
        else:
            self.s.units[key] = saved


def on_bound(handler, as_name, param, state, target, objects, zero_allowed=False):
    """The handler of `as_name` run with the object the call's `param`
    names bound for the call alone (self.s.<state>, read by the handler at
    `target`): a framebuffer for drawing (0, the window's, only where the
    call takes it) or a renderbuffer; a name that is no object
    (self.s.<objects>: bound once or created) makes the call do nothing,
    in every profile."""
    def h(self, no, name, a, args):
        d = dict(args)
        obj = checked(no, integer, d.get(param), f"{name}: the {param}", *U32)
        if (not obj and not zero_allowed) or obj and obj not in getattr(self.s, objects):
            return   # GL_INVALID_OPERATION
        saved = getattr(self.s, state)
        setattr(self.s, state, obj)
        args = [("target", target)] + [(k, v) for k, v in args if k != param]
        try:
            handler(self, no, as_name, [v for _, v in args], args)
        finally:
            setattr(self.s, state, saved)
    return h


def on_framebuffer(handler, as_name, default_allowed=False):
    return on_bound(handler, as_name, "framebuffer", "draw_fbo", "GL_DRAW_FRAMEBUFFER", "framebuffer_objects",
                    default_allowed)


def on_renderbuffer(handler, as_name):
    return on_bound(handler, as_name, "renderbuffer", "renderbuffer", "GL_RENDERBUFFER", "renderbuffer_objects")


class DirectStateCalls:
    def h_create_textures(self, no, name, a, args):
        """glCreateTextures(target, n, textures): textures that exist, of
        that target (glBindTexture's first bind makes a generated one)."""
        d = dict(args)
        n = checked(no, integer, d.get("n"), f"{name}: n", *I32)
        names = d.get("textures")
        if n < 0 or not isinstance(names, list):
            return   # GL_INVALID_VALUE (apitrace recorded no names)
        if len(names) != n or n > MAX_CREATED:
            fail_call(no, f"{name}: {len(names)} names, not its count ({n})")
        target = d.get("target")
        if not isinstance(target, str) or not target.startswith("GL_TEXTURE"):
            return   # GL_INVALID_ENUM
        if self.s.texture_names is None:
            self.s.texture_names = set()   # (as glGenTextures's first call makes it)
        for tex in names:
            tex = checked(no, integer, tex, f"{name}: a texture", *U32)
            if tex:
                self.s.texture_targets[tex] = target
                self.s.texture_names.add(tex)

    def h_texture_image_ext(self, no, name, a, args):
        """glTextureImage1D/2D/3DEXT (EXT_direct_state_access, compatibility
        profile): glTexImage1D/2D/3D on the texture it names at the target
        it gives (a name not yet bound becomes a texture of that target; a
        texture of another target is GL_INVALID_OPERATION and keeps its
        images)."""
        d = dict(args)
        tex = checked(no, integer, d.get("texture"), f"{name}: the texture", *U32)
        bound = ext_texture(self, tex, d.get("target"), faces=True)
        if bound is None:
            return   # GL_INVALID_ENUM, or a texture of another target: GL_INVALID_OPERATION (R29-1)
        as_name = base_name(name).replace("Texture", "Tex")
        handler = FramebufferCalls.h_tex_image if as_name == "glTexImage2D" else TextureLevelCalls.h_tex_image_any
        # (the call's own target: a cube map's face stays the face)
        run_bound(self, tex, bound, handler, no, as_name, [(k, v) for k, v in args if k != "texture"])

    HANDLERS = {
        "glCreateTextures": h_create_textures,
        "glTextureImage1D": h_texture_image_ext,   # the EXT forms' base names
        "glTextureImage2D": h_texture_image_ext,
        "glTextureImage3D": h_texture_image_ext,
        "glTextureStorage1D": on_texture(TextureLevelCalls.h_tex_image_any, "glTexStorage1D"),
        "glTextureStorage3D": on_texture(TextureLevelCalls.h_tex_image_any, "glTexStorage3D"),
        "glTextureStorage3DMultisample": on_texture(TextureLevelCalls.h_tex_image_any, "glTexStorage3DMultisample"),
        "glTextureStorage2D": on_texture(FramebufferCalls.h_tex_image, "glTexStorage2D"),
        "glTextureStorage2DMultisample": on_texture(FramebufferCalls.h_tex_image, "glTexStorage2DMultisample"),
        "glTextureSubImage2D": on_texture(FramebufferCalls.h_tex_sub_image, "glTexSubImage2D"),
        "glCompressedTextureSubImage2D": on_texture(FramebufferCalls.h_tex_sub_image, "glCompressedTexSubImage2D"),
        "glGenerateTextureMipmap": on_texture(TextureImageCalls.h_keep, "glGenerateMipmap"),
        "glCopyTextureSubImage2D": on_texture(TextureImageCalls.h_copy_tex_image, "glCopyTexSubImage2D"),
        "glTextureBuffer": on_texture(FramebufferCalls.h_tex_buffer, "glTexBuffer", "GL_TEXTURE_BUFFER"),
        "glTextureBufferRange": on_texture(FramebufferCalls.h_tex_buffer, "glTexBufferRange", "GL_TEXTURE_BUFFER"),
        "glNamedFramebufferTexture": on_framebuffer(FramebufferCalls.h_framebuffer_texture, "glFramebufferTexture"),
        "glNamedFramebufferTextureLayer": on_framebuffer(FramebufferCalls.h_framebuffer_texture_layer,
                                                         "glFramebufferTextureLayer"),
        "glNamedFramebufferRenderbuffer": on_framebuffer(FramebufferCalls.h_framebuffer_texture,
                                                         "glFramebufferRenderbuffer"),
        "glClearNamedFramebufferfv": on_framebuffer(PerFragmentCalls.h_clear_buffer, "glClearBufferfv", True),
        "glClearNamedFramebufferfi": on_framebuffer(PerFragmentCalls.h_clear_buffer, "glClearBufferfi", True),
        "glNamedRenderbufferStorage": on_renderbuffer(FramebufferCalls.h_renderbuffer_storage,
                                                      "glRenderbufferStorage"),
        "glNamedRenderbufferStorageMultisample": on_renderbuffer(FramebufferCalls.h_renderbuffer_storage,
                                                                 "glRenderbufferStorageMultisample"),
    } | {f"glTextureParameter{t}": on_texture(TextureImageCalls.h_keep, f"glTexParameter{t}")
         for t in ("i", "f", "iv", "fv", "Iiv", "Iuiv")}

"""The 2D textures and sampler objects a draw's vertex shader reads, given to
Mesa: the calls that made them (glstate/textures.py) replayed into Mesa's
context, once per version, through Mesa's own entry points (EGL's
eglGetProcAddress, with no wrapper between: Mesa reads the pixels as the
driver read them, and reports its errors where the driver did, which leave
the texture as the capture's driver left it).

Before a call is replayed, its pixels are checked to hold what GL reads for
its size, format, type and unpack state (GL 4.5, 8.4.4.1): Mesa would read
past them."""
import contextlib
import ctypes

import numpy as np

from ..cli import I32, U32, integer
from .errors import checked, fail_call, printable
from .glstate.texture_formats import MAX_SIZE
from .glstate.textures import (DEFAULT_TEXTURE_BASE, IMAGE_UNIT_BASE, LEVEL_CALLS, PARAMETER_CALLS,
                               READ_BACK_CALLS, SAMPLER_PARAMETER_CALLS, SAMPLES_CALL, UNPACK_PARAMETERS,
                               VERTEX_TEXTURE_TARGET, pixel_bytes)

# The images Mesa holds for vertex shaders, in all, counted at 16 bytes a
# texel (the widest format), a third more for a mipmapped storage: Mesa
# allocates a level's size whatever pixels a call gives.
MAX_MESA_TEXTURE_BYTES = 1 << 30
# The texture unit Mesa's copies are made on, before each is bound where a
# draw reads it (llvmpipe's last of 192).
SCRATCH_UNIT = 0x84C0 + 191
ANISOTROPY = ("GL_TEXTURE_MAX_ANISOTROPY", "GL_TEXTURE_MAX_ANISOTROPY_EXT", 0x84FE)
# Every sampler type a vertex shader may read, with its texture's target
# (those of other targets than 2D read back from Mesa's replay).
SAMPLER_TARGETS = {f"GL_{kind}SAMPLER_{shape}{shadow}": f"GL_TEXTURE_{target}"
                   for shape, target in (("2D", "2D"), ("1D", "1D"), ("3D", "3D"), ("CUBE", "CUBE_MAP"),
                                         ("1D_ARRAY", "1D_ARRAY"), ("2D_ARRAY", "2D_ARRAY"),
                                         ("2D_RECT", "RECTANGLE"), ("CUBE_MAP_ARRAY", "CUBE_MAP_ARRAY"),
                                         ("2D_MULTISAMPLE", "2D_MULTISAMPLE"),
                                         ("2D_MULTISAMPLE_ARRAY", "2D_MULTISAMPLE_ARRAY"))
                   for kind, shadow in (("", ""), ("INT_", ""), ("UNSIGNED_INT_", ""), ("", "_SHADOW"))
                   if not (shadow and shape in ("3D", "2D_MULTISAMPLE", "2D_MULTISAMPLE_ARRAY"))}
# A multisample texture's samples as read back (format, type): the sampler
# prefix and the 2D array format that holds them exactly.
SAMPLE_KINDS = {("GL_RGBA", "GL_FLOAT"): ("", 0x8814), ("GL_RGBA_INTEGER", "GL_INT"): ("i", 0x8D82),
                ("GL_RGBA_INTEGER", "GL_UNSIGNED_INT"): ("u", 0x8D70)}   # GL_RGBA32F, _32I, _32UI
# Image types a vertex shader may read (every target: read back from
# Mesa's replay, or of a buffer texture).
IMAGE_TARGETS = {f"GL_{kind}IMAGE_{shape}" for shape in ("1D", "2D", "3D", "2D_RECT", "CUBE", "BUFFER", "1D_ARRAY",
                                                          "2D_ARRAY", "CUBE_MAP_ARRAY", "2D_MULTISAMPLE",
                                                          "2D_MULTISAMPLE_ARRAY")
                 for kind in ("", "INT_", "UNSIGNED_INT_")}
u, i, e, f, sz, p = ctypes.c_uint, ctypes.c_int, ctypes.c_uint, ctypes.c_float, ctypes.c_int, ctypes.c_void_p
# Entry points and their C arguments after the target (or sampler).
ENTRY_POINTS = {
    "glTexImage2D": (e, i, i, sz, sz, i, e, e, p),
    "glTexImage1D": (e, i, i, sz, i, e, e, p),
    "glTexImage3D": (e, i, i, sz, sz, sz, i, e, e, p),
    "glTexSubImage2D": (e, i, i, i, sz, sz, e, e, p),
    "glTexStorage2D": (e, sz, e, sz, sz),
    "glTexStorage1D": (e, sz, e, sz),
    "glTexStorage3D": (e, sz, e, sz, sz, sz),
    "glTexSubImage1D": (e, i, i, sz, e, e, p),
    "glTexSubImage3D": (e, i, i, i, i, sz, sz, sz, e, e, p),
    "glCompressedTexImage2D": (e, i, e, sz, sz, i, sz, p),
    "glCompressedTexSubImage2D": (e, i, i, i, sz, sz, e, sz, p),
    "glGenerateMipmap": (e,),
    "glPixelStorei": (e, i),
} | {n: (e, e, f if n.endswith("f") else i) for n in ("glTexParameteri", "glTexParameterf")} \
  | {n: (e, e, p) for n in ("glTexParameteriv", "glTexParameterfv", "glTexParameterIiv", "glTexParameterIuiv")} \
  | {n: (u, e, f if n.endswith("f") else i) for n in ("glSamplerParameteri", "glSamplerParameterf")} \
  | {n: (u, e, p) for n in ("glSamplerParameteriv", "glSamplerParameterfv", "glSamplerParameterIiv",
                            "glSamplerParameterIuiv")}
ARGUMENTS = {
    "glTexImage2D": ("target", "level", "internalformat", "width", "height", "border", "format", "type", "pixels"),
    "glTexImage1D": ("target", "level", "internalformat", "width", "border", "format", "type", "pixels"),
    "glTexImage3D": ("target", "level", "internalformat", "width", "height", "depth", "border", "format", "type",
                     "pixels"),
    "glTexSubImage2D": ("target", "level", "xoffset", "yoffset", "width", "height", "format", "type", "pixels"),
    "glTexStorage2D": ("target", "levels", "internalformat", "width", "height"),
    "glTexStorage1D": ("target", "levels", "internalformat", "width"),
    "glTexStorage3D": ("target", "levels", "internalformat", "width", "height", "depth"),
    "glTexSubImage1D": ("target", "level", "xoffset", "width", "format", "type", "pixels"),
    "glTexSubImage3D": ("target", "level", "xoffset", "yoffset", "zoffset", "width", "height", "depth", "format",
                        "type", "pixels"),
    "glCompressedTexImage2D": ("target", "level", "internalformat", "width", "height", "border", "imageSize",
                               "data"),
    "glCompressedTexSubImage2D": ("target", "level", "xoffset", "yoffset", "width", "height", "format",
                                  "imageSize", "data"),
    "glGenerateMipmap": ("target",),
} | {n: ("target", "pname", "param") for n in ("glTexParameteri", "glTexParameterf")} \
  | {n: ("target", "pname", "params") for n in PARAMETER_CALLS if n.endswith("v")} \
  | {n: ("sampler", "pname", "param") for n in ("glSamplerParameteri", "glSamplerParameterf")} \
  | {n: ("sampler", "pname", "param") for n in SAMPLER_PARAMETER_CALLS if n.endswith("v")}
# (apitrace names glTexParameter*v's values params, glSamplerParameter*v's
# param.)
ENUM_ARGUMENTS = {"target", "internalformat", "format", "type", "pname"}


class VertexTextures:
    def __init__(self, mesa, watchdog=None):
        self.mesa, self.gl = mesa, mesa.gl
        self.watchdog = watchdog   # (mesa.Watchdog: the replay's read-back waits aside from Mesa's work)
        self.images = {}     # capture texture -> (Mesa texture, version replayed, bytes counted)
        self.image_bytes = 0
        self.samplers = {}   # capture sampler -> (Mesa sampler, parameters replayed)
        self.entry = {}
        self.no = self.draw = None   # the draw's call and name, for messages
        self.core = False            # the capture's context is of a core profile

    def call(self, name, *args):
        fn = self.entry.get(name)
        if fn is None:
            fn = self.entry[name] = self.mesa.proc(name, *ENTRY_POINTS[name])
        fn(*args)

    def forget(self):
        GL = self.gl
        if self.images:
            GL.glDeleteTextures(len(self.images), [e[0] for e in self.images.values()])
        self.image_bytes = 0
        if self.samplers:
            GL.glDeleteSamplers(len(self.samplers), [m for m, _ in self.samplers.values()])
        self.images, self.samplers = {}, {}

    def bind(self, conv, no, name, mp, buffer_texture):
        """Binds, at every unit the program's samplers name, the capture's
        texture there and its sampler object, and at every image unit its
        images name the texture level the capture bound there: a 2D texture
        from the calls that made it, one the GPU renders or of another target
        read back from Mesa's replay (conv.rendered_textures; a reduced
        capture carries those), a buffer texture by buffer_texture(conv,
        texture); each texture read is noted for the reduced capture
        (conv.vertex_texture_read)."""
        GL = self.gl
        self.no, self.draw = no, name
        self.core = conv.core and not conv.es
        unit_of = np.zeros(1, np.int32)
        reads, ask = [], []
        for loc, target in mp.texture_locations:
            GL.glGetUniformiv(mp.name, loc, unit_of)
            unit = int(unit_of[0])
            self.read(conv, unit, conv.s.units.get((unit, target), 0), target, reads, ask)
        images = []
        for loc in mp.image_locations:
            GL.glGetUniformiv(mp.name, loc, unit_of)
            unit = int(unit_of[0])
            binding = conv.s.image_units.get(unit)
            target = conv.s.texture_targets.get(binding[0]) if binding else None
            if binding is not None and target != "GL_TEXTURE_BUFFER":
                self.read(conv, IMAGE_UNIT_BASE + unit, binding[0], target, reads, ask)
            images.append((unit, binding, target))
        got = {}
        if ask:
            with self.watchdog.aside() if self.watchdog is not None else contextlib.nullcontext():
                got = conv.rendered_textures(no, name, ask)
        # Every texture made first (on the scratch unit), then each bound
        # where the draw reads it: making one must not replace another
        # already bound.
        made = {}
        for unit, tex, tc, target in reads:
            tc = got.get((tex, target), tc)
            made[(tex, target)] = self.image(tex, tc, target)
            conv.vertex_texture_read(tex, tc)
        images = [self.image_binding(conv, unit, binding, target, made, buffer_texture)
                  for unit, binding, target in images]
        if not conv.es:
            # (OpenGL ES's cube maps are always seamless, and it has no
            # texture unit bias: Mesa's ES context keeps its own.)
            (GL.glEnable if conv.s.cube_seamless else GL.glDisable)(GL.GL_TEXTURE_CUBE_MAP_SEAMLESS)
        for unit, tex, _, target in reads:
            if unit >= IMAGE_UNIT_BASE:
                continue
            sampler = conv.s.sampler_units.get(unit, 0)
            ms = self.sampler(sampler, conv.s.samplers.get(sampler, {})) if sampler else 0
            GL.glActiveTexture(GL.GL_TEXTURE0 + unit)
            GL.glBindTexture(self.mesa.enum(target), made[(tex, target)])
            GL.glBindSampler(unit, ms)
            if not conv.es:
                GL.glTexEnvf(GL.GL_TEXTURE_FILTER_CONTROL, GL.GL_TEXTURE_LOD_BIAS, conv.s.unit_lod_bias.get(unit, 0.0))
        GL.glActiveTexture(GL.GL_TEXTURE0)
        self.bind_images(images)

    def image_binding(self, conv, unit, binding, target, made, buffer_texture):
        """(unit, Mesa texture, level, layered, layer, access, format) of
        image unit `unit` as the capture bound it (texture 0: unbound): the
        texture made for the draw, in the capture's format or, bound by
        glBindImageTextures, the texture's own."""
        GL = self.gl
        if binding is None:
            return unit, 0, 0, 0, 0, GL.GL_READ_ONLY, GL.GL_R8
        tex, level, layered, layer, access, fmt = binding
        GL.glActiveTexture(SCRATCH_UNIT)
        if target == "GL_TEXTURE_BUFFER":
            mt = buffer_texture(conv, tex)
        else:
            mt = made[(tex, target)]
        if fmt is None:
            GL.glBindTexture(self.mesa.enum(target), mt)
            fmt = int(GL.glGetTexLevelParameteriv(self.level_target(target), 0, GL.GL_TEXTURE_INTERNAL_FORMAT))
        GL.glActiveTexture(GL.GL_TEXTURE0)
        return unit, mt, level, 1 if layered else 0, layer, self.mesa.enum(access), self.mesa.enum(fmt)

    def bind_images(self, images):
        """Mesa's image units bound (image_binding's tuples), through Mesa's
        entry point called directly (PyOpenGL's wrapper cannot read an OpenGL
        ES context's version); what Mesa refuses, the replay's refused too
        (a format the texture's image does not take): that unit reads as
        unbound."""
        GL = self.gl
        u, i = ctypes.c_uint, ctypes.c_int
        bind = self.mesa.proc("glBindImageTexture", u, u, i, ctypes.c_ubyte, i, u, u)
        for args in images:
            self.drain()
            bind(*args)
            if GL.glGetError():
                bind(args[0], 0, 0, 0, 0, GL.GL_READ_ONLY, GL.GL_R8)

    def read(self, conv, unit, tex, target, reads, ask):
        """Notes that the draw reads texture `tex` of `target` at `unit` (a
        texture unit, or IMAGE_UNIT_BASE + an image unit), and whether
        Mesa's replay must give it."""
        if not tex and target != VERTEX_TEXTURE_TARGET:
            # The target's default texture, which may hold an image as any
            # other (kept apart from the 2D one's calls, under a name of its
            # own); Mesa's replay reads it at the unit as any other.
            from .rendered_textures import TARGETS
            tex = DEFAULT_TEXTURE_BASE + TARGETS[target]
        tc = conv.s.texture_calls.get(tex)
        if target == VERTEX_TEXTURE_TARGET:
            if tc is not None and (tc.rendered or tc.refused is not None):
                # The GPU renders it, or its calls cannot be given to
                # Mesa (a pixel unpack buffer, over the limits): Mesa's
                # replay of the capture gives the image.
                ask.append((unit, tex, tc, target))
        elif not (conv.reads_reduced and tc is not None):
            # No calls are kept for other targets: Mesa's replay gives
            # the texture (a reduced capture carries what it gave).
            ask.append((unit, tex, None, target))
        reads.append((unit, tex, tc if target == VERTEX_TEXTURE_TARGET or conv.reads_reduced else None, target))

    def image(self, tex, tc, target=VERTEX_TEXTURE_TARGET):
        GL = self.gl
        version = tc.version if tc is not None else 0
        entry = self.images.get((tex, target))
        if entry is not None and entry[1] == version:
            return entry[0]
        if entry is not None:
            GL.glDeleteTextures(1, [entry[0]])
            self.image_bytes -= entry[2]
            del self.images[(tex, target)]
        size = 0
        for _, name, d, _ in (tc.calls.values() if tc is not None else []):
            if name in LEVEL_CALLS + READ_BACK_CALLS + ("glTexStorage2D",):
                w, h, depth = d.get("width"), d.get("height", 1), d.get("depth", 1)
                if all(isinstance(v, int) and v > 0 for v in (w, h, depth)):
                    size += w * h * depth * 16 * (4 if name == "glTexStorage2D" else 3) // 3
        if self.image_bytes + size > MAX_MESA_TEXTURE_BYTES:
            fail_call(self.no, f"{self.draw}: texture {tex}, which its vertex shader reads: the textures given to "
                      f"Mesa would take more than {MAX_MESA_TEXTURE_BYTES >> 30} GiB (docs/gl-capture.md, limits)")
        self.image_bytes += size
        mt = int(GL.glGenTextures(1))
        self.images[(tex, target)] = (mt, version, size)
        GL.glActiveTexture(SCRATCH_UNIT)
        GL.glBindTexture(self.mesa.enum(target), mt)
        for call_no, name, d, unpack in (tc.calls.values() if tc is not None else []):
            what = f"{self.draw}: texture {tex}, which its vertex shader reads: {name} (call {call_no})"
            if name == SAMPLES_CALL:
                self.fill_samples(what, mt, d)
            else:
                self.replay(what, name, d, unpack)
        for pname in UNPACK_PARAMETERS:
            self.call("glPixelStorei", self.mesa.enum(pname), 4 if pname == "GL_UNPACK_ALIGNMENT" else 0)
        self.drain()
        if self.core:
            self.core_depth(target)
        # llvmpipe's vertex shaders do not wait for its rasterizer threads:
        # the levels glGenerateMipmap renders are finished before a draw
        # reads them.
        GL.glFinish()
        GL.glActiveTexture(GL.GL_TEXTURE0)
        return mt

    def fill_samples(self, what, mt, d):
        """Multisample texture `mt` (bound on the scratch unit) given its storage and
        every sample of every layer as read back (d: SAMPLES_CALL's
        arguments): the samples uploaded as the layers of a 2D array
        texture, then drawn into mt, one sample at a time under a sample
        mask, by a full-screen triangle whose fragment shader fetches its
        pixel of the layer (depth formats through gl_FragDepth). Nothing is
        filled if Mesa refuses the storage (the texture reads as zeros)."""
        GL, no = self.gl, self.no
        self.drain()   # (the raw calls before it leave their errors)
        w, h, depth, samples = (checked(no, integer, d.get(k), f"{what}: {k}", 1, MAX_SIZE)
                                for k in ("width", "height", "depth", "samples"))
        fixed = checked(no, integer, d.get("fixedsamplelocations"), f"{what}: fixedsamplelocations", 0, 1)
        fmt, kind, pixels = d.get("format"), d.get("type"), d.get("pixels")
        if depth % samples or (fmt, kind) not in SAMPLE_KINDS or not isinstance(pixels, (bytes, bytearray)) \
                or len(pixels) != w * h * depth * 16:
            fail_call(no, f"{what}: not a multisample image as the read back gives one")
        target = self.mesa.enum(d.get("target"))
        layers = depth // samples
        GL.glActiveTexture(SCRATCH_UNIT)
        GL.glBindTexture(target, mt)
        try:
            internal = self.mesa.enum(d.get("internalformat"))
        except ValueError:
            fail_call(no, f"{what}: internal format {printable(d.get('internalformat'))} is not an enumerant")
        # Mesa's entry points called directly (PyOpenGL's wrappers of these
        # cannot read an OpenGL ES context's version).
        u, i = ctypes.c_uint, ctypes.c_int
        proc = self.mesa.proc
        if target == GL.GL_TEXTURE_2D_MULTISAMPLE:
            proc("glTexStorage2DMultisample", u, i, u, i, i, ctypes.c_ubyte)(target, samples, internal, w, h, fixed)
        else:
            proc("glTexStorage3DMultisample", u, i, u, i, i, i, ctypes.c_ubyte)(target, samples, internal, w, h,
                                                                                 layers, fixed)
        if GL.glGetError():
            return   # Mesa refuses the storage (its replay did not)
        prefix, sampler_kind = SAMPLE_KINDS[(fmt, kind)]
        depth_format = GL.glGetTexLevelParameteriv(target, 0, GL.GL_TEXTURE_DEPTH_SIZE) > 0
        version = "#version 300 es\nprecision highp float;\nprecision highp int;\n" if self.mesa.es \
            else "#version 330\n"
        vs = version + "void main() { gl_Position = vec4(vec2(gl_VertexID & 1, gl_VertexID >> 1) * 4.0 - 1.0, " \
            "0.0, 1.0); }\n"
        fetch = "texelFetch(src, ivec3(gl_FragCoord.xy, layer), 0)"
        fs = version + f"uniform highp {prefix}sampler2DArray src;\nuniform int layer;\n" + (
            f"void main() {{ gl_FragDepth = {fetch}.r; }}\n" if depth_format else
            f"out highp {prefix}vec4 colour;\nvoid main() {{ colour = {fetch}; }}\n")
        prog, shaders = GL.glCreateProgram(), []
        for stage, text in ((GL.GL_VERTEX_SHADER, vs), (GL.GL_FRAGMENT_SHADER, fs)):
            sh = GL.glCreateShader(stage)
            GL.glShaderSource(sh, text)
            GL.glCompileShader(sh)
            GL.glAttachShader(prog, sh)
            shaders.append(sh)
        GL.glLinkProgram(prog)
        src, fb = int(GL.glGenTextures(1)), int(GL.glGenFramebuffers(1))
        GL.glBindTexture(GL.GL_TEXTURE_2D_ARRAY, src)
        data = ctypes.create_string_buffer(bytes(pixels), len(pixels))
        self.call("glTexImage3D", GL.GL_TEXTURE_2D_ARRAY, 0, sampler_kind, w, h, depth, 0, self.mesa.enum(fmt),
                  self.mesa.enum(kind), ctypes.addressof(data))
        # One level, nearest: complete, integer formats too.
        GL.glTexParameteri(GL.GL_TEXTURE_2D_ARRAY, GL.GL_TEXTURE_MIN_FILTER, GL.GL_NEAREST)
        GL.glTexParameteri(GL.GL_TEXTURE_2D_ARRAY, GL.GL_TEXTURE_MAG_FILTER, GL.GL_NEAREST)
        GL.glBindFramebuffer(GL.GL_FRAMEBUFFER, fb)
        attachment = GL.GL_DEPTH_ATTACHMENT if depth_format else GL.GL_COLOR_ATTACHMENT0
        in_use = GL.glGetIntegerv(GL.GL_CURRENT_PROGRAM)   # the draw's, already in use
        GL.glUseProgram(prog)
        GL.glUniform1i(GL.glGetUniformLocation(prog, "src"), SCRATCH_UNIT - GL.GL_TEXTURE0)
        sampler = GL.glGetIntegerv(GL.GL_SAMPLER_BINDING)   # (of the scratch unit, active)
        GL.glBindSampler(SCRATCH_UNIT - GL.GL_TEXTURE0, 0)   # the array's own nearest filtering
        if not self.mesa.es:
            GL.glEnable(GL.GL_FRAMEBUFFER_SRGB)   # an sRGB texture's samples, read decoded, encoded again
        GL.glViewport(0, 0, w, h)
        GL.glEnable(GL.GL_SAMPLE_MASK)
        sample_mask = proc("glSampleMaski", u, u)
        if depth_format:
            GL.glEnable(GL.GL_DEPTH_TEST)
            GL.glDepthFunc(GL.GL_ALWAYS)
        layer_at = GL.glGetUniformLocation(prog, "layer")
        try:
            for z in range(layers):
                if target == GL.GL_TEXTURE_2D_MULTISAMPLE:
                    GL.glFramebufferTexture2D(GL.GL_FRAMEBUFFER, attachment, target, mt, 0)
                else:
                    proc("glFramebufferTextureLayer", u, u, u, i, i)(GL.GL_FRAMEBUFFER, attachment, mt, 0, z)
                if GL.glCheckFramebufferStatus(GL.GL_FRAMEBUFFER) != GL.GL_FRAMEBUFFER_COMPLETE:
                    break   # a format Mesa cannot draw into: left as zeros
                for s in range(samples):
                    sample_mask(0, 1 << s)
                    GL.glUniform1i(layer_at, z * samples + s)
                    GL.glDrawArrays(GL.GL_TRIANGLES, 0, 3)
        finally:
            sample_mask(0, 0xFFFFFFFF)
            GL.glDisable(GL.GL_SAMPLE_MASK)
            GL.glBindSampler(SCRATCH_UNIT - GL.GL_TEXTURE0, int(sampler))
            if not self.mesa.es:
                GL.glDisable(GL.GL_FRAMEBUFFER_SRGB)
            GL.glDisable(GL.GL_DEPTH_TEST)
            GL.glUseProgram(in_use)
            GL.glBindFramebuffer(GL.GL_FRAMEBUFFER, self.mesa.fbo)   # the vertex stage's own
            GL.glDeleteFramebuffers(1, [fb])
            GL.glDeleteTextures(1, [src])
            for sh in shaders:
                GL.glDeleteShader(sh)
            GL.glDeleteProgram(prog)
            GL.glBindTexture(target, mt)

    def level_target(self, target):
        """The target a texture's level is asked about at (a cube map's
        first face)."""
        return self.gl.GL_TEXTURE_CUBE_MAP_POSITIVE_X if target == "GL_TEXTURE_CUBE_MAP" else self.mesa.enum(target)

    def core_depth(self, target):
        """A depth texture of a core profile's capture reads as (d, 0, 0,
        1) there; Mesa's compatibility context (GLSL 1.30 and later) reads
        it as (d, d, d, 1) whatever GL_DEPTH_TEXTURE_MODE says: the
        texture's swizzle (the capture's own, made after it) is given the
        core profile's components."""
        GL = self.gl
        t = self.mesa.enum(target)
        if not GL.glGetTexLevelParameteriv(self.level_target(target), 0, GL.GL_TEXTURE_DEPTH_SIZE) or \
                GL.glGetTexParameteriv(t, GL.GL_DEPTH_STENCIL_TEXTURE_MODE) == GL.GL_STENCIL_INDEX:
            return
        core = {GL.GL_GREEN: GL.GL_ZERO, GL.GL_BLUE: GL.GL_ZERO, GL.GL_ALPHA: GL.GL_ONE}
        swizzle = [int(v) for v in GL.glGetTexParameteriv(t, GL.GL_TEXTURE_SWIZZLE_RGBA)]
        GL.glTexParameteriv(t, GL.GL_TEXTURE_SWIZZLE_RGBA, np.array([core.get(v, v) for v in swizzle], np.int32))

    def sampler(self, sampler, params):
        GL = self.gl
        state = [call for calls in params.values() for call in calls]
        for _, d in state:
            pname = d.get("pname")
            value = d.get("param")
            value = value[0] if isinstance(value, list) and len(value) == 1 else value   # (a *v form's)
            if pname in ANISOTROPY and not (isinstance(value, (int, float)) and value <= 1):
                # Measured: the draw kills Mesa's llvmpipe with SIGSEGV (the
                # capture's own program died there too).
                fail_call(self.no, f"{self.draw}: sampler {sampler}, bound where its vertex shader reads, filters "
                          "anisotropically: Mesa 22.3's llvmpipe crashes on such a draw; not emulated")
        entry = self.samplers.get(sampler)
        if entry is not None and entry[1] == state:
            return entry[0]
        if entry is not None:
            GL.glDeleteSamplers(1, [entry[0]])
        ms = int(GL.glGenSamplers(1))
        self.samplers[sampler] = (ms, state)
        for name, d in state:
            self.replay(f"{self.draw}: sampler {sampler}, bound where its vertex shader reads: {name}", name,
                        dict(d, sampler=ms), None)
        self.drain()
        return ms

    def drain(self):
        """Mesa's errors from the calls replayed: the capture's driver
        ignored those calls as Mesa did."""
        while self.gl.glGetError():
            pass

    def replay(self, what, name, d, unpack):
        """Call `name` of a texture or sampler (`what` names it in messages)
        into Mesa; its arguments checked as the C call takes them."""
        no = self.no
        if unpack is not None:
            for pname, value in zip(UNPACK_PARAMETERS, unpack):
                self.call("glPixelStorei", self.mesa.enum(pname), value)
        args, keep = [], []
        for key, ctype in zip(ARGUMENTS[name], ENTRY_POINTS[name]):
            v = d.get(key)
            if key == "sampler":
                args.append(v)
            elif key in ("pixels", "data"):
                args.append(self.pixels(what, name, d, unpack, v, keep))
            elif key == "params" or key == "param" and name.endswith("v"):
                if not isinstance(v, list) or not v or len(v) > 4:
                    fail_call(no, f"{what}: parameter values that are not a list of one to four numbers")
                kind = np.float32 if name.endswith("fv") else np.uint32 if name.endswith("uiv") else np.int32
                try:
                    arr = np.zeros(4, kind)
                    arr[:len(v)] = [self.mesa.enum(x) if isinstance(x, str) else x for x in v]
                except (ValueError, TypeError, OverflowError):
                    fail_call(no, f"{what}: a parameter value of no type GL takes")
                keep.append(arr)
                args.append(arr.ctypes.data)
            elif key in ENUM_ARGUMENTS or key == "param" and isinstance(v, str):
                try:
                    args.append(checked(no, integer, self.mesa.enum(v), f"{what}: {key}", *U32))
                except ValueError:
                    fail_call(no, f"{what}: {key} {printable(v)} is not an enumerant")
            elif ctype is f:
                if isinstance(v, bool) or not isinstance(v, (int, float)):
                    fail_call(no, f"{what}: {key} is not a number")
                args.append(float(v))
            else:
                args.append(checked(no, integer, v, f"{what}: {key}", *I32))
        self.call(name, *args)

    def pixels(self, what, name, d, unpack, v, keep):
        """The address of a call's pixels, checked to hold what Mesa reads."""
        no = self.no
        if v is None or isinstance(v, int) and not isinstance(v, bool) and v == 0:
            return None   # NULL: the level allocated, its contents undefined
        if not isinstance(v, (bytes, bytearray)):
            fail_call(no, f"{what}: its pixels are not in the reduced capture (a draw that reads the texture "
                      "carries them)")
        if name.startswith("glCompressed"):
            need = checked(no, integer, d.get("imageSize"), f"{what}: imageSize", *I32)
        else:
            need = pixel_bytes(no, what, d, unpack)
            if need is None:
                fail_call(no, f"{what}: pixels of format {printable(d.get('format'))} and type "
                          f"{printable(d.get('type'))} are not emulated for a texture a vertex shader reads")
        if len(v) < need:
            fail_call(no, f"{what}: {len(v)} bytes of pixels, {need} read by GL for its size, format and "
                      "unpack state")
        buf = ctypes.create_string_buffer(bytes(v), len(v))
        keep.append(buf)
        return ctypes.addressof(buf)

"""The GL state that decides where a fragment lands and whether it reaches the
unit, and the handlers of the calls that change it, one module a state group:

    transform       matrix stacks, viewport, depth range, user clip planes
    per_fragment    scissor, depth test and writes, clears, glEnable/glDisable
    polygon         culling, winding, polygon offset and mode
    vertex_arrays   the vertex array and buffer objects
    draws           draw calls and immediate mode, into draw records
    objects         which object a draw is: debug groups, selection rules
    buffers         buffer objects: contents, bindings, mapped writes
    attributes      generic attributes and vertex array objects
    programs        shaders, programs, uniforms and uniform blocks
    framebuffers    which pass a draw writes; texture buffers a vertex shader reads
    textures        2D texture images and sampler objects a vertex shader reads
    dsa             direct state access on textures, framebuffers, renderbuffers

Each module holds a mixin of rbcd.gl2rbt.converter.Converter whose HANDLERS
map GL function names (without ARB/EXT) to its handlers, called as
h(self, call_no, name, argument values, (name, value) arguments)."""
import re

import numpy as np

from ...cli import I32, integer, real
from ..errors import checked, fail_call, printable
from ..gl_tables import MAX_CLIP_PLANES
from .attributes import VertexArrayObject

# ---------------------------------------------------------------- the GL state

class Array:
    __slots__ = ("size", "type", "stride", "data", "buffer", "offset")

    def __init__(self):
        self.size, self.type, self.stride, self.data, self.buffer, self.offset = 4, "GL_FLOAT", 0, None, 0, 0


class GLState:
    def __init__(self):
        I = np.identity(4)
        # Mesa has no colour matrix (ARB_imaging): glMatrixMode(GL_COLOR) is
        # GL_INVALID_ENUM there.
        self.stacks = {"GL_MODELVIEW": [I.copy()], "GL_PROJECTION": [I.copy()], "GL_TEXTURE": [I.copy()]}
        self.mode = "GL_MODELVIEW"
        self.viewport = None
        self.scissor = None
        self.scissor_test = False
        self.depth_range = (0.0, 1.0)
        self.clip_control = None       # (call, origin, depth) of a glClipControl other than GL's default
        self.depth_test = False
        self.depth_func = "GL_LESS"
        self.depth_mask = True
        self.clear_depth = 1.0
        self.cull = False
        self.cull_face = "GL_BACK"
        self.front_face = "GL_CCW"
        self.provoking_first = False   # glProvokingVertex(GL_FIRST_VERTEX_CONVENTION)
        self.offset_fill = False
        self.offset_other = set()      # GL_POLYGON_OFFSET_LINE, _POINT enabled (refused with an offset)
        self.offset = (0.0, 0.0)
        self.clip_planes = [None] * MAX_CLIP_PLANES
        self.clip_enabled = [False] * MAX_CLIP_PLANES
        # Buffer objects (buffers.py): contents, versions, bindings, mappings.
        self.buffers = {}
        self.buffer_versions = {}
        self.buffer_written = {}   # large buffers: the [start, end) extents ever written
        self.buffer_held = {}      # buffer -> bytes of memory its data holds
        self.buffer_names = None   # names glGenBuffers returned (None: the capture showed none)
        self.buffer_objects = set()   # buffer objects that exist: bound once, or made by glCreateBuffers
        self.immutable_buffers = {}   # made by glBufferStorage: buffer -> GL_DYNAMIC_STORAGE_BIT set
        self.buffer_bytes_in_all = 0
        self.next_version = 0
        self.bound = {"GL_ARRAY_BUFFER": 0, "GL_ELEMENT_ARRAY_BUFFER": 0}
        self.indexed = {}
        self.mappings = {}
        self.gpu_buffers = {}   # buffer -> (call, how) the GPU wrote it (its contents are not the capture's)
        # Generic attributes and vertex array objects (attributes.py).
        self.vaos = {0: VertexArrayObject()}
        self.vao = 0
        self.attrib_values = {}
        self.restart = False
        self.restart_fixed = False
        self.restart_index = 0
        self.rasterizer_discard = False
        # Blend factors and draw buffers (color_outputs.py): each draw
        # buffer's factors (GL_ONE, GL_ZERO), and how many colour draw
        # buffers the window (GL_BACK: one) and each framebuffer object
        # (GL_COLOR_ATTACHMENT0: one, unless listed) have.
        from .color_outputs import DEFAULT_BLEND, MAX_DRAW_BUFFERS   # (it imports this module)
        self.blend_factors = [DEFAULT_BLEND] * MAX_DRAW_BUFFERS
        self.window_draw_buffers = 1
        self.fbo_draw_buffers = {}
        # Whether only colour output 0 is drawn, into one buffer (not
        # GL_FRONT_AND_BACK), on the window and each framebuffer object, and
        # the advanced blend equation (KHR_blend_equation_advanced) in use.
        self.window_one_output = True
        self.fbo_one_output = {}
        # Mesa's completeness status of each framebuffer object as it keeps
        # it (_Status): True complete, False incomplete, absent untested (a
        # new one, or one whose attachments or their images changed since);
        # each framebuffer's draw buffers as glDrawBuffer(s) named them; and
        # whether a change Mesa flags _NEW_BUFFERS for is pending, which has
        # the next state update (a draw, a clear: FramebufferCalls.
        # update_framebuffers) test the bound framebuffers not found complete.
        self.fbo_status = {}
        self.fbo_answered = set()    # those whose status is the capture's answer to a status check
        # Each framebuffer object's integer colour attachment at its last
        # test (Mesa's _IntegerBuffers): its (point, format), None, or why
        # it is not known (a str); FramebufferCalls.integer_attachment.
        self.fbo_integer = {}
        # Textures' levels as completeness reads them (texture_levels.py):
        # ("texture", name) -> TextureLevels; an image-giving call passed over.
        self.texture_levels = {}
        self.images_passed_over = None
        self.fbo_buffer_names = {}
        self.window_buffer_names = ("GL_BACK",)
        self.new_buffers = False
        self.advanced_blend = None
        self.blend_on = False             # GL_BLEND (any draw buffer's)
        self.render_fault = None          # why draws are refused, as Mesa last decided (DrawCalls.revalidate)
        # Shaders and programs (programs.py).
        self.shaders = {}
        self.programs = {}
        self.program = 0
        self.pipelines = {}    # program pipeline name -> Pipeline
        self.pipeline = 0      # the bound pipeline (draws run it when no program is in use)
        # Framebuffers and textures (framebuffers.py).
        self.draw_fbo = 0
        self.read_fbo = 0
        self.fbo_depth = {}
        self.fbo_attachments = {}   # framebuffer -> {colour or stencil attachment point: image, as fbo_depth's}
        self.sizes = {}
        self.formats = {}   # ("texture" | "renderbuffer", name) -> internal format of level 0
        self.depth_types = {}   # ("texture", name) -> the pixels' type its level 0 was given
        self.multisampled = {}   # the same -> its samples as llvmpipe gives them (4), or 0 for none
        self.renderbuffer = 0
        self.framebuffer_names = None    # names glGen/glCreateFramebuffers returned (None: the capture showed none)
        self.renderbuffer_names = None   # the same for renderbuffers
        # Framebuffer and renderbuffer objects: names bound once or made by
        # glCreate* and not deleted since (a name glGen* returned is no
        # object until bound: direct state access on it is
        # GL_INVALID_OPERATION in Mesa, as on any other name).
        self.framebuffer_objects = set()
        self.renderbuffer_objects = set()
        self.deleted_images = 0   # deleted textures and renderbuffers that live on for framebuffers not bound
        self.active_unit = 0
        self.unit_lod_bias = {}        # texture unit -> its GL_TEXTURE_LOD_BIAS (glTexEnv), when not 0
        self.cube_seamless = False     # GL_TEXTURE_CUBE_MAP_SEAMLESS
        self.units = {}
        self.texture_targets = {}   # texture -> the target it was first bound to
        self.texture_names = None   # names glGenTextures gave and no glDeleteTextures freed (None: none seen)
        self.sampler_names = None   # the same for glGenSamplers and glCreateSamplers
        self.texture_buffers = {}
        self.texture = 0
        self.texture_images = {}   # texture name: digest of its level-0 image, or None
        # 2D textures' images and sampler objects (textures.py).
        self.texture_calls = {}    # texture name -> TextureCalls
        self.texture_bytes_kept = 0
        self.unpack = {}           # glPixelStorei's unpack state, where not GL's default
        self.pixel_transfer = {}   # glPixelTransfer's parameters as last set
        self.samplers = {}         # sampler name -> {pname: (call name, arguments)}
        self.sampler_units = {}    # unit -> sampler name
        # Image units (glBindImageTexture): unit -> (texture, level, layered,
        # layer, access, format); the units bound for writing.
        self.image_units = {}
        self.image_writes = set()
        # Transform feedback (feedback.py): the bound object, whether it is
        # active and paused, the program it records from; the primitive
        # mode last begun; the objects not bound.
        self.feedback = (0, False, False)
        self.feedback_source = None
        self.feedback_mode = None
        self.feedback_objects = {}
        self.feedback_ended = set()   # the objects ended at least once (Mesa's EndedAnytime)
        # Tessellation (programs.py): vertices a patch, default levels set.
        self.patch_vertices = 3
        self.patch_levels = {}
        self.views = set()   # textures that share images with another (glTextureView)
        # --reduced-out: the version of each texture's calls written into
        # the reduced capture (with a draw whose vertex shader read it).
        self.reduced_texture_versions = {}
        # Textures the GPU renders: the draws, clears and copies that may
        # have written one so far, and each one's image as last read back
        # from Mesa's replay (TextureImageCalls.rendered_textures).
        self.gpu_writes = 0
        self.rendered_images = {}
        self.readback_call = None   # (the last call Mesa's replay read textures back at, those textures)
        self.groups = []   # innermost last: object id or None
        self.group_names = []   # the same groups: (object id or None, message)
        self.marker = ""        # the last message the application inserted in the frame
        self.begin_mode = None
        self.begin_verts = []
        self.begin_cuts = []     # glPrimitiveRestartNV between glBegin and glEnd: vertex counts at each
        # glRenderMode: GL_SELECT and GL_FEEDBACK draw and glClear no pixel.
        self.render_mode = "GL_RENDER"
        self.list_compiling = False

    # The fixed-function vertex array (glVertexPointer, GL_VERTEX_ARRAY) is
    # state of the bound vertex array object, as generic attributes are.
    @property
    def vertex_array(self):
        vao = self.vaos[self.vao]
        if vao.fixed is None:
            vao.fixed = Array()
        return vao.fixed

    @property
    def vertex_array_enabled(self):
        return self.vaos[self.vao].fixed_enabled

    @vertex_array_enabled.setter
    def vertex_array_enabled(self, on):
        self.vaos[self.vao].fixed_enabled = on


# The state contexts of one share group hold in common: the objects Mesa
# shares (buffers, textures, renderbuffers, samplers, shaders and programs,
# and framebuffer objects, which GL does not share but Mesa 22.3 keeps
# with the others, so that a framebuffer a loader context made is the
# drawing context's in Mesa's replay; not vertex array objects or program
# pipelines), with what the converter keeps of them; and counters of the
# whole conversion. Every other field of GLState, the bindings included, is
# a context's own (converter.Converter.h_make_current).
SHARED_STATE = {
    "buffers", "buffer_versions", "buffer_written", "buffer_held", "buffer_names", "buffer_objects",
    "immutable_buffers", "mappings", "gpu_buffers", "shaders", "programs", "sizes", "formats",
    "depth_types",
    "multisampled", "renderbuffer_names", "deleted_images", "texture_targets", "texture_names", "sampler_names",
    "texture_buffers", "texture_images", "texture_calls", "samplers", "views", "reduced_texture_versions",
    "rendered_images", "fbo_depth", "fbo_attachments", "fbo_draw_buffers", "fbo_one_output", "fbo_status", "fbo_buffer_names", "texture_levels",
    "images_passed_over", "framebuffer_names", "framebuffer_objects", "renderbuffer_objects", "fbo_answered",
    "fbo_integer"}
# The memory limits are of all groups together.
CONVERSION_STATE = {"next_version", "gpu_writes", "readback_call", "buffer_bytes_in_all", "texture_bytes_kept"}


MAX_VIEWPORTS = 16   # GL_MAX_VIEWPORTS as Mesa (llvmpipe) answers it


def first_of_array(no, name, d, what, size_of):
    """glViewportArrayv's and glScissorArrayv's rectangle 0 (four values),
    or None when the call sets no rectangle 0: GL_INVALID_VALUE for the
    whole call past Mesa's 16 or with any negative size (size_of reads a
    size, checked), or a range from another index."""
    first = checked(no, integer, d.get("first"), f"{name}: first", *I32)
    count = checked(no, integer, d.get("count"), f"{name}: count", *I32)
    v = d.get("v")
    if not isinstance(v, list) or len(v) < 4 * max(count, 0):
        fail_call(no, f"{name}: fewer values than four a {what}")
    if first < 0 or count < 0 or first + count > MAX_VIEWPORTS or \
            any(size_of(x, no, f"{name}: a {what} size") < 0 for i in range(count) for x in v[4 * i + 2:4 * i + 4]):
        return None
    return v[:4] if first == 0 and count else None


def generated_name(core, names, n):
    """Whether a core profile binds `n` as the name of an object whose names
    glGen*/glCreate* hand out (`names`: those they returned and no glDelete*
    freed since): 0 or such a name; another is GL_INVALID_OPERATION in Mesa
    22.3 (the earlier binding stays). `names` None: the capture showed no
    glGen* of the kind (a reduced capture written before they were kept),
    taken as it binds."""
    return not (core and n and names is not None and n not in names)


def bitfield(mask, no, what, bits):
    """A GLbitfield as apitrace records it (bit names, alone, joined by "|"
    or in a list, or a number) as the names of `bits` (value -> name) it
    sets, and whether it sets a bit `bits` does not name; any other value
    is the capture's error."""
    names, unknown = set(), False
    for p in mask if isinstance(mask, (list, tuple)) else (mask,):
        if isinstance(p, str):
            names |= {n.strip() for n in p.split("|")} - {"0"}
        elif isinstance(p, int) and not isinstance(p, bool) and 0 <= p < 1 << 32:
            names |= {n for v, n in bits.items() if p & v}
            unknown = unknown or bool(p & ~sum(bits))
        else:
            fail_call(no, f"{what}: {printable(mask, 40)} is not a bitfield")
    return names, unknown


# An enumerant's name as apitrace's tables spell them.
ENUM_NAME = re.compile(r"(GL|GLX|EGL|WGL)_[A-Za-z0-9_]{1,120}")   # (ASTC names have an x)


def enum_arg(v, no, what):
    """An enumerant as apitrace records it: its name, or a number for a
    value it has no name for (which GL answers with GL_INVALID_ENUM); any
    other value (a string no table spells, a line end or an escape in
    it: a capture altered) is the capture's error."""
    if (isinstance(v, str) and ENUM_NAME.fullmatch(v)) or \
            (isinstance(v, int) and not isinstance(v, bool) and 0 <= v < 1 << 32):
        return v
    fail_call(no, f"{what}: {printable(v, 40)} is not an enumerant (a name, or a 32-bit value)")


def gl_boolean(v, no, what, nonzero=False):
    """A GLboolean argument as the driver keeps it: GL_TRUE/GL_FALSE, or the
    byte the application passed, of which a one-bit state keeps the low bit
    (Mesa: glDepthMask(2) writes no depth), or, `nonzero`, any byte but 0 is
    true (Mesa tests the argument as C does: glVertexAttribPointer's
    normalized, glUniformMatrix's transpose)."""
    if v == "GL_TRUE" or v is True:
        return True
    if v == "GL_FALSE" or v is False:
        return False
    if type(v) is int and 0 <= v < 256:   # not a float equal to one (1.0 == True)
        return v != 0 if nonzero else bool(v & 1)
    fail_call(no, f"{what}: {printable(v, 40)} is not a GLboolean (an unsigned byte)")


def clamped01(v, no, what):
    """A value GL clamps to [0, 1] (depth range, clear depth): infinities
    clamp; NaN, whose clamp GL leaves undefined, is refused."""
    if isinstance(v, float) and v in (float("inf"), float("-inf")):
        return 1.0 if v > 0 else 0.0
    return min(1.0, max(0.0, number(v, no, what)))


def parameter_value(d):
    """A parameter call's value, a vector form's first (apitrace names
    glTexParameter*v's values `params`, glSamplerParameter*v's `param`);
    None for an empty list."""
    v = d.get("param", d.get("params"))
    return (v[0] if v else None) if isinstance(v, list) else v


def number(v, no, what):
    """A finite number from the capture (GL leaves infinities and NaN in
    most calls' results unspecified: refused, naming the call)."""
    return checked(no, real, v, what)

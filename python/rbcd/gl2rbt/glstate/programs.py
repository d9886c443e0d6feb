"""Shaders, programs and their uniforms (OpenGL 2.0+ and ES): what the shader
path's vertex stage needs to build each program in Mesa and give it the
capture's uniform values. A program is built from what its last
glLinkProgram saw: the sources of its shaders as last compiled and its
attribute bindings (apitrace adds the bindings the link chose, as fake
glBindAttribLocation calls, so that a replay's locations are the capture's).
Uniform locations and block indices are the capture's; their names come from
the capture's own glGetUniformLocation and glGetUniformBlockIndex calls (a
location no call named is an explicit one, the same in Mesa)."""
import copy
import hashlib
import re

from ...cli import I32, U32, integer, real
from ..errors import checked, fail_call, printable
from ..gl_tables import base_name
from . import enum_arg, gl_boolean
from .glsl_text import COMMENTS, MAX_CHOICES, MAX_DEPTH, MAX_TOKENS, ExpansionTooLarge, expanded

STAGES = {"GL_VERTEX_SHADER": "vertex", "GL_FRAGMENT_SHADER": "fragment", "GL_GEOMETRY_SHADER": "geometry",
          "GL_TESS_CONTROL_SHADER": "tess_control", "GL_TESS_EVALUATION_SHADER": "tess_evaluation",
          "GL_COMPUTE_SHADER": "compute"}
MAX_SOURCE_CHARS = 16 << 20   # one shader's sources (the largest game shaders are tens of kilobytes)
# Operators and separators in one statement of a shader (between ;, { and }):
# Mesa's compiler recurses once a term, and a sum of 20,000 terms overflowed
# its default stack (scripts/rbcd-gl2rbt gives it 2 GiB, on which much
# longer ones compile). Game shaders' longest statements have tens.
MAX_STATEMENT_OPERATORS = 65536
STATEMENTS = re.compile(r"[^;{}]+")
OPERATORS = re.compile(r"[-+*/%&|^<>?:=,!~]")
# A shader storage block that is not readonly (the qualifiers of its
# declaration, back to the statement before), or an atomic counter: a
# stage that may store into buffers.
STORAGE_BLOCK = re.compile(r"\bbuffer\s+\w+\s*\{")
ATOMIC_COUNTER = re.compile(r"\batomic_uint\b")
READONLY = re.compile(r"\breadonly\b")


def may_store(text):
    """Whether a stage's text as glsl_text.expanded reads it stores."""
    if ATOMIC_COUNTER.search(text):
        return True
    for m in STORAGE_BLOCK.finditer(text):
        start = max(text.rfind(c, 0, m.start()) for c in ";{}") + 1
        if not READONLY.search(text, start, m.start()):
            return True
    return False
UNIFORM = re.compile(r"gl(Program)?Uniform(Matrix)?([1-4])(x[2-4])?(f|d|i|ui)(v?)$")
# glUseProgramStages' bits (GL 4.6 table 7.1) and its "every stage".
STAGE_BITS = {"GL_VERTEX_SHADER_BIT": "vertex", "GL_FRAGMENT_SHADER_BIT": "fragment",
              "GL_GEOMETRY_SHADER_BIT": "geometry", "GL_TESS_CONTROL_SHADER_BIT": "tess_control",
              "GL_TESS_EVALUATION_SHADER_BIT": "tess_evaluation", "GL_COMPUTE_SHADER_BIT": "compute"}
STAGE_BIT_VALUES = {1 << i: stage for i, stage in enumerate(STAGE_BITS.values())}   # (in the bits' order)
# The stages in the order primitives pass them (Mesa's gl_shader_stage).
PIPELINE_ORDER = ["vertex", "tess_control", "tess_evaluation", "geometry", "fragment", "compute"]
# A sampler type's shape in GLSL (sampler2D, isamplerCubeArray,
# sampler2DShadow: 2D, CubeArray, 2D), which gives its texture target; and
# the glUniform forms that set a sampler's unit.
SAMPLER_TYPE = re.compile(r"\b[iu]?sampler([0-9A-Z]\w*?)(?:Shadow)?\b")
SAMPLER_SETTERS = ("glUniform1i", "glUniform1iv")
MAX_TEXTURE_UNITS = 192   # llvmpipe's GL_MAX_COMBINED_TEXTURE_IMAGE_UNITS: a unit past it is refused


class Shader:
    __slots__ = ("stage", "sources", "compiled")

    def __init__(self, stage):
        self.stage, self.sources, self.compiled = stage, [], None


# GL_MAX_PATCH_VERTICES as Mesa 22.3 (llvmpipe) answers it.
MAX_PATCH_VERTICES = 32
# Outputs one glTransformFeedbackVaryings may name (Mesa links at most 128
# components interleaved, each output at least one).
MAX_FEEDBACK_VARYINGS = 128


class Program:
    def __init__(self):
        self.shaders = set()
        self.bindings = {}         # attribute name -> index
        self.linked = None         # ({stage: source}, {name: index}) at the last link
        self.objects = {}          # {stage: [source of each shader object]} at the last link
        self.link_call = None
        self.version = 0           # a new one at each link
        self.uniform_names = {}    # capture location -> name
        self.block_names = {}      # capture block index -> name
        # (capture location, function, count) -> (function, values, transpose,
        # component type, count): the last values each form of glUniform set
        # at a location, in the order last set (Mesa ignores a form its
        # uniform lacks, and the last form it takes holds).
        self.uniforms = {}
        self.deleted = False       # glDeleteProgram while in use
        self.block_bindings = {}   # capture block index -> binding point
        self.discards = False      # its fragment shader has a discard statement
        self.stores = False        # a stage declares shader storage blocks or atomic counters
        self.scanned = {}          # {stage: its source as the compiler reads it} at the last link (glsl_text)
        self.frag_depth = False    # its fragment shader writes gl_FragDepth
        self.digest = ""           # SHA-256 of its stages' sources at the last link (selection rules)
        self.separable = False     # GL_PROGRAM_SEPARABLE as its last link saw it
        self.separable_next = False   # as glProgramParameteri last set it, for the next link
        # The capture's own transform feedback outputs ((names, buffer mode)
        # or None), as glTransformFeedbackVaryings last set them, for the
        # next link, and at the last link: Mesa links with them to decide
        # whether the capture's link succeeded.
        self.feedback_next = self.feedback = None
        # Linked again while in use: the program as it was (its executable
        # and uniforms), which stays in use if this link fails
        # (program_in_use).
        self.in_use_before = None
        # The shapes of sampler its stages' texts declare, at the last link
        # (only two or more can put two types on one unit), how many
        # glUniform1i(v) calls it has had since (the sampler units the
        # capture may have set), and Mesa's validation of its samplers
        # for that count (VertexStage.sampler_validation).
        self.sampler_shapes = frozenset()
        self.int_uniform_calls = 0
        self.samplers_checked = None
        self.sampler_uniforms = None   # (its link, the names and locations of its samplers in Mesa's link)
        self.sampler_units = {}        # capture location -> the unit a glUniform1i(v) last set there


class Pipeline:
    """A program pipeline object (GL 4.1, ES 3.1): the separable program
    of each stage, the active one glUniform* sets, and whether Mesa
    validated it (pipe->Validated: kept until glUseProgramStages changes
    it or a sampler's glUniform1i, whatever is relinked meanwhile)."""
    __slots__ = ("stages", "active", "validated")

    def __init__(self):
        self.stages, self.active, self.validated = {}, 0, False   # stage -> program name


def sources_digest(sources):
    """The digest selection rules name a program by: its stages' sources."""
    return hashlib.sha256("".join(f"{stage}\0{sources[stage]}\0" for stage in sorted(sources))
                          .encode("utf-8", "surrogateescape")).hexdigest()


def uniform_values(no, name, kind, values):
    """A glUniform's values as the C types of its form take them: a float
    or double any number a double holds (NaN and infinities are values a
    shader may be given), an int or unsigned int its 32 bits."""
    for v in values:
        if kind in ("i", "ui"):
            checked(no, integer, v, f"{name}: a value", *(I32 if kind == "i" else U32))
        elif isinstance(v, bool) or not isinstance(v, (int, float)):
            fail_call(no, f"{name}: the values are not numbers")
        elif isinstance(v, int):
            checked(no, real, v, f"{name}: a value")   # an integer past a double's range is refused


def name_arg(no, name, v, what):
    if not isinstance(v, int) or v < 0:
        fail_call(no, f"{name}: impossible {what} {printable(v)}")
    return v


class ProgramCalls:
    """self.s.shaders, self.s.programs: capture name -> Shader, Program."""

    def program(self, no, name, v):
        """Program `v` of the call; for a name that is no program (never
        created, deleted, a shader's), one no one holds: GL_INVALID_VALUE or
        GL_INVALID_OPERATION, and the call changes nothing."""
        p = self.s.programs.get(name_arg(no, name, v, "program"))
        return p if p is not None else Program()

    def vertex_program(self):
        """Whether draws now run a vertex shader: the program in use, or
        with none the bound pipeline, has one (a program of only a fragment
        shader leaves the vertices to the fixed-function transform, in a
        compatibility context)."""
        return "vertex" in self.stage_programs()

    def program_in_use(self):
        """The program whose executable draws run: the one in use as its last
        link made it, or, when that link was made while it was in use and
        fails in Mesa, the executable it had, with its uniforms (GL 4.6
        §7.3, and Mesa: a failed relink leaves the last executable in use,
        glUniform and glUseProgram of the program are then
        GL_INVALID_OPERATION, until another program is used)."""
        return self.executable(self.s.programs[self.s.program])

    def executable(self, p):
        while p.in_use_before is not None and not self.vertex_stage().links(p):
            p = p.in_use_before
        return p

    def stage_programs(self):
        """{stage: (program name, Program as its executable)} of what draws
        run: every stage of the program in use, or, with none in use, the
        stages of the bound program pipeline (GL 4.6 §7.4)."""
        if self.s.program in self.s.programs:
            p = self.program_in_use()
            return {stage: (self.s.program, p) for stage in p.linked[0]} if p.linked else {}
        pipe = self.s.pipelines.get(self.s.pipeline)
        if pipe is None:
            return {}
        out = {}
        for stage, v in pipe.stages.items():
            p = self.executable(self.s.programs[v]) if v in self.s.programs else None
            if p is not None and stage in p.linked[0]:   # (a relink may have taken the stage away)
                out[stage] = (v, p)
        return out

    def pipeline_invalid(self):
        """Why the bound pipeline draws nothing, when no program is in use
        (GL 4.6 §11.1.3.11: GL_INVALID_OPERATION at the draw, under a
        program's stages or the fixed-function ones alike), as Mesa 22.3
        validates it (_mesa_validate_program_pipeline): no program for any
        stage; a program active for some of the stages it links and not
        others; a program's stages on both sides of another's; a
        tessellation or geometry stage with no vertex stage; a program
        linked again without GL_PROGRAM_SEPARABLE. None when it draws.
        Asked when Mesa decides (DrawCalls.revalidate)."""
        pipe = self.current_pipeline()
        if pipe is None or pipe.validated:
            return None
        why = self.pipeline_fault(pipe)
        pipe.validated = why is None
        return why

    def samplers_invalid(self):
        """Why the program in use draws nothing for its samplers: active
        samplers of different types on one texture unit (GL 4.6
        §11.1.3.11), as Mesa 22.3 follows it for a program used by
        glUseProgram (_mesa_sampler_uniforms_are_valid, when it decides).
        None when it draws; a pipeline's samplers are part of its
        validation (pipeline_fault)."""
        if self.s.program not in self.s.programs:
            return None
        p = self.program_in_use()
        if p.linked is None or len(p.sampler_shapes) < 2 or self.vertex_stage().sampler_validation(p)[0]:
            return None
        return f"program {self.s.program} has active samplers of different types on one texture unit"

    def pipeline_fault(self, pipe):
        """Why pipeline `pipe`, bound, fails Mesa's validation; None when it
        passes (pipeline_invalid)."""
        where = f"pipeline {self.s.pipeline[1] if isinstance(self.s.pipeline, tuple) else self.s.pipeline}"
        if not pipe.stages:
            return f"{where} has no program for any stage"
        for v in set(pipe.stages.values()):
            p = self.s.programs.get(v)
            if p is None or not p.linked:
                continue
            # (A compute stage is no draw's: a compute program beside the
            # others, or alone, leaves the draws to them.)
            linked = {stage for stage in p.linked[0] if stage != "compute"}
            if {stage for stage, w in pipe.stages.items() if w == v and stage != "compute"} != linked:
                return f"program {v} is in {where}'s stages for some of its stages, not all"
        stages = self.stage_programs()
        order = [v for stage, (v, _) in sorted(stages.items(), key=lambda kv: PIPELINE_ORDER.index(kv[0]))]
        for i in range(1, len(order)):
            if order[i] != order[i - 1] and order[i] in order[:i]:
                return f"program {order[i]} is in {where}'s stages before and after another program's"
        if "vertex" not in stages and stages.keys() & {"tess_control", "tess_evaluation", "geometry"}:
            return f"{where} has a tessellation or geometry stage and no vertex stage"
        for v, p in stages.values():
            if not p.separable:
                return f"program {v}, in {where}, was linked again without GL_PROGRAM_SEPARABLE"
        if len(set().union(*(p.sampler_shapes for _, p in stages.values()))) >= 2:
            # Two types of sampler on one unit across the stages, unit 0
            # aside (Mesa 22.3 _mesa_sampler_uniforms_pipeline_are_valid:
            # every sampler starts there).
            targets = {}
            for stage in sorted(stages, key=PIPELINE_ORDER.index):
                v, p = stages[stage]
                for unit, target in self.vertex_stage().sampler_validation(p)[1].get(stage, ()):
                    if unit and targets.setdefault(unit, target) != target:
                        return f"program {v}, in {where}, reads texture unit {unit} as a second type of texture"
        return None

    def draw_digest(self):
        """The digest of the sources of what draws run, every stage (a
        pipeline of the stages of a program is named as the program)."""
        if self.s.program in self.s.programs:
            return self.program_in_use().digest
        return sources_digest({stage: p.linked[0][stage] for stage, (_, p) in self.stage_programs().items()})

    def in_a_pipeline(self, v):
        return any(v in pipe.stages.values() for pipe in self.s.pipelines.values())

    def in_use_elsewhere(self, v):
        """Program v is in use in another live context of the current one's
        share group (its program, or a stage of one of its pipelines): a
        deletion waits for it too."""
        here = getattr(self, "state_context", None)
        if here is None:
            return False
        group = self.share_group(here)
        for ctx, state in self.context_states.items():
            if ctx == here or ctx in self.destroyed_contexts or self.share_group(ctx) != group:
                continue
            if state.get("program") == v or any(v in pipe.stages.values()
                                               for pipe in state.get("pipelines", {}).values()):
                return True
        return False

    def h_create_shader(self, no, name, a, args):
        stage = STAGES.get(a[0] if a else None)
        if stage is None or not isinstance(self.ret, int):
            fail_call(no, f"{name}: not a shader type")
        self.s.shaders[self.ret] = Shader(stage)

    def h_shader_source(self, no, name, a, args):
        d = dict(args)
        strings, lengths = d.get("string"), d.get("length")
        if not isinstance(strings, list) or not all(isinstance(s, str) for s in strings):
            fail_call(no, f"{name}: sources that are not text")
        count = checked(no, integer, d.get("count", len(strings)), f"{name}: the count", *I32)
        shader = d.get("shader")
        if type(shader) is not int:   # (h_create_shader_program's own shader is -1)
            fail_call(no, f"{name}: impossible shader {printable(shader)}")
        sh = self.s.shaders.get(shader)
        if sh is None or count < 0:
            # GL_INVALID_VALUE (no such shader, or a negative count, whose
            # sources apitrace records as none), GL_INVALID_OPERATION (a
            # program's name): the source stays
            return
        if count != len(strings):
            fail_call(no, f"{name}: {len(strings)} sources, not its count ({count})")
        if isinstance(lengths, list):
            strings = [s if not isinstance(n, int) or n < 0 else s[:n] for s, n in zip(strings, lengths)]
        total = sum(len(s) for s in strings)
        if total > MAX_SOURCE_CHARS:
            fail_call(no, f"{name}: {total} characters of source, more than {MAX_SOURCE_CHARS} "
                      "(docs/gl-capture.md, limits)")
        text = COMMENTS.sub(" ", "".join(strings))
        if len(OPERATORS.findall(text)) > MAX_STATEMENT_OPERATORS:   # a cheap bound before the exact count
            longest = max(len(OPERATORS.findall(m.group())) for m in STATEMENTS.finditer(text))
            if longest > MAX_STATEMENT_OPERATORS:
                fail_call(no, f"{name}: a statement of {longest} operators, more than {MAX_STATEMENT_OPERATORS} "
                          "(docs/gl-capture.md, limits): Mesa's compiler would overflow its stack")
        sh.sources = strings

    def h_compile_shader(self, no, name, a, args):
        sh = self.s.shaders.get(name_arg(no, name, a[0] if a else None, "shader"))
        if sh is None:
            return   # GL_INVALID_VALUE, or GL_INVALID_OPERATION for a program's name: nothing is compiled
        sh.compiled = "".join(sh.sources)

    def h_create_program(self, no, name, a, args):
        if not isinstance(self.ret, int):
            fail_call(no, f"{name}: no program name recorded")
        self.s.programs[self.ret] = Program()

    def h_attach_shader(self, no, name, a, args):
        d = dict(args)
        p = self.program(no, name, d.get("program"))
        s = name_arg(no, name, d.get("shader"), "shader")
        if s not in self.s.shaders:
            return   # GL_INVALID_VALUE or GL_INVALID_OPERATION: nothing is attached or detached
        (p.shaders.add if name.startswith("glAttach") else p.shaders.discard)(s)

    def h_bind_attrib_location(self, no, name, a, args):
        d = dict(args)
        p = self.program(no, name, d.get("program"))
        index = checked(no, integer, d.get("index"), f"{name}: the index", *U32)
        attr = d.get("name")
        if not isinstance(attr, str):
            fail_call(no, f"{name}: the attribute name {printable(attr, 40)} is not text")
        if index >= 64:
            return   # GL_INVALID_VALUE past GL_MAX_VERTEX_ATTRIBS (below 64, Mesa's link answers the same)
        p.bindings[attr] = index

    def h_link_program(self, no, name, a, args):
        p = self.program(no, name, a[0] if a else None)
        if self.records_from(a[0]):
            return   # GL_INVALID_OPERATION: transform feedback records from it (paused too)
        before = None
        if (a[0] == self.s.program or self.in_a_pipeline(a[0])) and p.linked is not None:
            before = copy.copy(p)
            if before.in_use_before is not None and self.vertex_stage().links(before):
                before.in_use_before = None   # that link held: what it replaced is out of use
        sources, objects = {}, {}
        for s in sorted(p.shaders):
            sh = self.s.shaders[s]
            if sh.compiled is None:
                fail_call(no, f"{name}: shader {s} was never compiled")
            # Several shader objects of one stage are linked together (each
            # compiled on its own); the stage's source, which rules and
            # checks read, is their texts joined.
            objects.setdefault(sh.stage, []).append(sh.compiled)
            if sh.stage in sources:
                sources[sh.stage] += "\n" + sh.compiled
            else:
                sources[sh.stage] = sh.compiled
        self.linked(no, p, sources, objects)
        p.in_use_before = before

    @staticmethod
    def linked(no, p, sources, objects):
        """Program p linked at call `no` from these stages (joined source
        and each shader object's)."""
        p.linked, p.objects = (sources, dict(p.bindings)), objects
        p.digest = sources_digest(sources)
        p.separable = p.separable_next
        p.feedback = p.feedback_next
        # Each stage's text as the compiler reads it (macros expanded, every
        # branch kept: glsl_text), shader object by shader object (each is
        # preprocessed alone: one's macros are not another's), for the scans
        # below and the vertex stage's refusals.
        try:
            p.scanned = {stage: "\n;\n".join(expanded(text) for text in objects.get(stage, [sources[stage]]))
                         for stage in sources}
        except ExpansionTooLarge:
            fail_call(no, f"program linked at call {no}: its shaders' macros expand past {MAX_TOKENS} tokens, "
                      f"{MAX_DEPTH} macros deep or {MAX_CHOICES} definitions of one (docs/gl-capture.md, limits)")
        fragment = p.scanned.get("fragment", "")
        # Whether any stage may store into buffers: shader storage blocks not
        # readonly, or atomic counters.
        p.stores = any(may_store(text) for text in p.scanned.values())
        p.discards = re.search(r"\bdiscard\b", fragment) is not None
        p.frag_depth = re.search(r"\bgl_FragDepth(EXT)?\b", fragment) is not None
        p.sampler_shapes = frozenset(m.group(1) for text in p.scanned.values() for m in SAMPLER_TYPE.finditer(text))
        p.link_call = no
        p.version += 1
        p.uniform_names, p.block_names, p.uniforms, p.block_bindings, p.sampler_units = {}, {}, {}, {}, {}

    def h_use_program(self, no, name, a, args):
        v = checked(no, integer, a[0] if a else None, f"{name}: the program", *U32)
        if v and (v not in self.s.programs or self.s.programs[v].linked is None) or self.recording():
            return   # GL_INVALID_VALUE or GL_INVALID_OPERATION (also while feedback records): the call does nothing
        if v and v != self.s.program and "vertex" in self.s.programs[v].linked[0] \
                and not self.vertex_stage().links(self.s.programs[v]):
            return   # its last link failed in Mesa: GL_INVALID_OPERATION, the program in use stays
        old, was = self.s.programs.get(self.s.program), self.s.program
        # glUseProgram(0) binds the bound pipeline again (Mesa 22.3), which
        # has Mesa decide whether draws are valid, a program in use or not.
        self.decides = not v and self.s.pipeline in self.s.pipelines
        self.s.program = v
        if old is not None and v != was:
            self.out_of_use(was)
        if not v and was and isinstance(self.s.pipeline, tuple):
            # Mesa's glUseProgram(0) after a program binds the current
            # pipeline again by its name, which a pipeline deleted while
            # bound (h_delete_pipelines) no longer has: GL_INVALID_OPERATION,
            # and no pipeline is in effect (Mesa 22.3 use_program; with no
            # program in use before, the call changes nothing).
            self.release_deleted_pipeline()

    def out_of_use(self, v):
        """Program v may have gone out of use (glUseProgram of another, a
        pipeline's stage given another): its old executable goes, and so
        does the program if it was deleted while in use."""
        p = self.s.programs.get(v)
        if p is None or v == self.s.program or self.in_a_pipeline(v) or self.in_use_elsewhere(v):
            return
        p.in_use_before = None
        if p.deleted:
            del self.s.programs[v]

    def h_delete_program(self, no, name, a, args):
        """glDeleteProgram: the name goes at once unless the program is in
        use, then when it no longer is (a later glUseProgram of it is
        GL_INVALID_VALUE, and the program in use stays)."""
        v = a[0] if a else None
        if not isinstance(v, int) or isinstance(v, bool) or v not in self.s.programs:
            return   # 0 is ignored; an unknown name is GL_INVALID_VALUE
        if v == self.s.program or self.in_a_pipeline(v) or self.in_use_elsewhere(v):
            self.s.programs[v].deleted = True   # gone once no pipeline nor context uses it
        else:
            del self.s.programs[v]

    def h_get_uniform_location(self, no, name, a, args):
        d = dict(args)
        p = self.program(no, name, d.get("program"))
        # A GLint: -1 (no such uniform) or a location.
        loc = checked(no, integer, self.ret, f"{name}: the location returned", -1, I32[1])
        if loc >= 0 and isinstance(d.get("name"), str):
            p.uniform_names[loc] = d["name"]

    def h_get_uniform_block_index(self, no, name, a, args):
        d = dict(args)
        p = self.program(no, name, d.get("program"))
        if isinstance(self.ret, int) and 0 <= self.ret < 0xFFFFFFFF and isinstance(d.get("uniformBlockName"), str):
            p.block_names[self.ret] = d["uniformBlockName"]

    def h_get_program_resource(self, no, name, a, args):
        """glGetProgramResourceLocation and glGetProgramResourceIndex (GL 4.3,
        ES 3.1): a uniform's location or a uniform block's index named as
        glGetUniformLocation and glGetUniformBlockIndex name them; other
        interfaces (inputs, outputs, storage blocks) set nothing the vertex
        stage is given by location."""
        d = dict(args)
        interface, rname = d.get("programInterface"), d.get("name")
        if "Location" in name and interface == "GL_UNIFORM":
            self.h_get_uniform_location(no, name, a, [("program", d.get("program")), ("name", rname)])
        elif "Index" in name and interface == "GL_UNIFORM_BLOCK":
            self.h_get_uniform_block_index(no, name, a, [("program", d.get("program")), ("uniformBlockName", rname)])

    def h_get_block_name(self, no, name, a, args):
        """glGetActiveUniformBlockName and glGetProgramResourceName of a
        uniform block (GL 4.3, ES 3.1): the name of the block at an index,
        which glUniformBlockBinding may then bind (an engine enumerating its
        program's blocks)."""
        d = dict(args)
        if "Resource" in name and d.get("programInterface") != "GL_UNIFORM_BLOCK":
            return
        idx = d.get("uniformBlockIndex", d.get("index"))
        block = d.get("uniformBlockName", d.get("name"))
        p = self.program(no, name, d.get("program"))
        if isinstance(idx, int) and not isinstance(idx, bool) and 0 <= idx < 0xFFFFFFFF and isinstance(block, str) \
                and block:
            p.block_names[idx] = block

    def h_uniform_block_binding(self, no, name, a, args):
        d = dict(args)
        p = self.program(no, name, d.get("program"))
        idx, binding = d.get("uniformBlockIndex"), d.get("uniformBlockBinding")
        if not isinstance(idx, int) or not isinstance(binding, int) or idx < 0 or not 0 <= binding < 1024:
            fail_call(no, f"{name}: impossible block index or binding")
        p.block_bindings[idx] = binding

    def h_uniform(self, no, name, a, args):
        """glUniform*, glUniformMatrix*, glProgramUniform*: kept per program
        and location, to be set in Mesa's program as the capture set them."""
        name = base_name(name)
        m = UNIFORM.match(name)
        if m is None:
            fail_call(no, f"{printable(name)} is not emulated")
        if m.group(1):
            p, rest = self.program(no, name, a[0] if a else None), a[1:]
        elif self.s.program:
            p, rest = self.s.programs[self.s.program], a
        else:
            # With no program in use, the bound pipeline's active program
            # (GL 4.6 §7.6.1); with neither, GL_INVALID_OPERATION: nothing.
            pipe = self.s.pipelines.get(self.s.pipeline)
            if pipe is None or pipe.active not in self.s.programs:
                return
            p, rest = self.s.programs[pipe.active], a
        loc = checked(no, integer, rest[0], f"{name}: the location", *I32)
        transpose = m.group(2) is not None and gl_boolean(dict(args).get("transpose"), no, f"{name}: transpose",
                                                          nonzero=True)
        if loc == -1:
            return   # GL ignores a location of -1
        values, count = rest[1:], None
        if m.group(6):   # the v forms: count, [transpose,] values
            count = checked(no, integer, dict(args).get("count"), f"{name}: the count", *I32)
            if count <= 0:
                # GL_INVALID_VALUE, or no value set (the pointer unread,
                # NULL too): the call changes nothing.
                return
            values = [v for v in values if isinstance(v, list)]
            if len(values) != 1:
                fail_call(no, f"{name}: the values are not numbers")
            values = values[0]
            rows, _, cols = (m.group(4) or "x").partition("x")
            width = int(m.group(3)) * (int(cols) if cols else int(m.group(3)) if m.group(2) else 1)
            if len(values) != count * width:
                fail_call(no, f"{name}: {len(values)} values, not its count ({count}) of {width}")
        elif len(values) != int(m.group(3)):
            fail_call(no, f"{name}: {len(values)} values, not {m.group(3)}")
        uniform_values(no, name, m.group(5), values)
        # As Mesa's program is given it: the glUniform function, the values,
        # their component type and, for the v forms, their count.
        # Kept in the order last set: an array's element and the array
        # itself name the same storage, and the later call wins.
        func = name.replace("glProgramUniform", "glUniform")
        key = (loc, func, count)
        p.uniforms.pop(key, None)
        p.uniforms[key] = (func, values, transpose, m.group(5), count)
        if func in SAMPLER_SETTERS:
            p.int_uniform_calls += 1
            if p.sampler_shapes and all(0 <= v < MAX_TEXTURE_UNITS for v in values):
                n = self.sampler_elements(p, loc, len(values))   # (0: no sampler there)
                if n:
                    self.sampler_set(p, loc, values[:n])   # (GL sets none past the array's end)

    def sampler_set(self, p, loc, values):
        """A glUniform1i(v) Mesa takes for a sampler of program p (elements
        from capture location loc on): Mesa clears the bound pipeline's
        validation, whichever program it is and changed or not
        (validate_uniform), and decides again whether draws are valid only
        when a sampler moved to another unit (_mesa_uniform's any_changed;
        a sampler starts at the unit Mesa's link gives it: its
        layout(binding), or 0)."""
        pipe = self.current_pipeline()
        if pipe is not None:
            pipe.validated = False
        units = p.sampler_units
        moved = any(units.get(loc + i, self.sampler_start_unit(p, loc, i)) != v for i, v in enumerate(values))
        units.update((loc + i, v) for i, v in enumerate(values))
        if moved:
            self.revalidate()

    def sampler_start_unit(self, p, loc, i):
        """The unit Mesa's link of program p gives sampler element i from
        capture location loc on (by the name the capture asked that
        location for, else by Mesa's own location)."""
        by_name, by_location = self.vertex_stage().sampler_start_units(p)
        uname = p.uniform_names.get(loc)
        if uname is None:
            return by_location.get(loc + i, 0)
        m = re.fullmatch(r"(.*)\[(\d+)\]", uname)
        base, first = (m.group(1), int(m.group(2))) if m else (uname, 0)
        return by_name.get(f"{base}[{first + i}]", 0)

    def sampler_elements(self, p, loc, count):
        """How many of `count` sampler elements from capture location loc
        on exist in Mesa's link of program p (Mesa clamps the count to the
        array's end); 0 when loc names no sampler."""
        names, locations = self.vertex_stage().sampler_uniforms(p)
        uname = p.uniform_names.get(loc)
        if uname is None:
            return next((i for i in range(count) if loc + i not in locations), count)
        m = re.fullmatch(r"(.*)\[(\d+)\]", uname)
        base, first = (m.group(1), int(m.group(2))) if m else (uname, 0)
        return next((i for i in range(count) if f"{base}[{first + i}]" not in names), count)

    def h_patch_parameter(self, no, name, a, args):
        """glPatchParameteri(GL_PATCH_VERTICES) and glPatchParameterfv's
        default tessellation levels, which Mesa's copy gets at a draw under
        tessellation; a value GL refuses changes nothing."""
        d = dict(args)
        pname = enum_arg(d.get("pname"), no, f"{name}: the parameter")
        if base_name(name) == "glPatchParameteri":
            v = checked(no, integer, d.get("value"), f"{name}: the value", *I32)
            if pname == "GL_PATCH_VERTICES" and 0 < v <= MAX_PATCH_VERTICES:
                self.s.patch_vertices = v
            return
        n = {"GL_PATCH_DEFAULT_OUTER_LEVEL": 4, "GL_PATCH_DEFAULT_INNER_LEVEL": 2}.get(pname)
        values = d.get("values")
        if n is None or not isinstance(values, list) or len(values) < n:
            if n is not None:
                fail_call(no, f"{printable(name)}: the capture does not hold its {n} levels")
            return   # GL_INVALID_ENUM
        # Any GLfloat, infinities and NaN too: Mesa computes them (a level
        # past 64 is 64, a NaN outer level drops the patch, as 0 does).
        self.s.patch_levels[pname] = tuple(v if isinstance(v, float) else checked(no, real, v, f"{name}: a level")
                                           for v in values[:n])

    def h_program_parameter(self, no, name, a, args):
        """glProgramParameteri: GL_PROGRAM_SEPARABLE, which the next link
        takes; the hint to keep the binary changes nothing drawn; another
        parameter or value is GL_INVALID_ENUM or _VALUE."""
        d = dict(args)
        pname, value = d.get("pname"), d.get("value")
        if pname == "GL_PROGRAM_SEPARABLE" and value in (0, 1, False, True, "GL_FALSE", "GL_TRUE"):
            self.program(no, name, d.get("program")).separable_next = value in (1, True, "GL_TRUE")

    def h_create_shader_program(self, no, name, a, args):
        """glCreateShaderProgramv (GL 4.1, ES 3.1): a separable program of
        one stage, compiled and linked at once from the sources."""
        d = dict(args)
        stage = STAGES.get(d.get("type"))
        if stage is None:
            return   # GL_INVALID_ENUM: no program made (it returns 0)
        if not isinstance(self.ret, int) or self.ret <= 0:
            return   # no program made (a count GL refuses)
        sh = Shader(stage)
        self.s.shaders[-1] = sh
        try:
            self.h_shader_source(no, name, a, [("shader", -1), ("count", d.get("count")),
                                                ("string", d.get("strings")), ("length", None)])
        finally:
            del self.s.shaders[-1]
        p = self.s.programs[self.ret] = Program()
        p.separable_next = True
        text = "".join(sh.sources)
        self.linked(no, p, {stage: text}, {stage: [text]})

    def pipeline(self, no, name, v):
        """Pipeline v (glGenProgramPipelines makes the objects, in Mesa);
        None for 0 or a name that is none (GL_INVALID_OPERATION)."""
        if not isinstance(v, int) or isinstance(v, bool) or not 0 <= v <= U32[1]:
            fail_call(no, f"{printable(name)}: impossible pipeline {printable(v)}")
        return self.s.pipelines.get(v)

    def h_gen_pipelines(self, no, name, a, args):
        d = dict(args)
        for v in d.get("pipelines") or []:
            if isinstance(v, int) and not isinstance(v, bool) and v > 0:
                self.s.pipelines.setdefault(v, Pipeline())

    def h_bind_pipeline(self, no, name, a, args):
        v = dict(args).get("pipeline", a[0] if a else None)
        if v == 0 and self.s.program in self.s.programs:
            # Mesa 22.3 returns at once when the name is its current
            # shader state's, the program's own (0) while one is in use:
            # the pipeline stays bound, and glUseProgram(0) brings it back.
            return
        if (v == 0 or self.pipeline(no, name, v) is not None) and not self.recording():
            # (while feedback records: GL_INVALID_OPERATION)
            if isinstance(self.s.pipeline, tuple):
                self.release_deleted_pipeline()   # a pipeline deleted while bound goes now
            self.s.pipeline = v

    def h_validate_pipeline(self, no, name, a, args):
        """glValidateProgramPipeline: Mesa validates the pipeline now, bound
        or not (pipe->Validated: one that passed is not validated again
        until glUseProgramStages or a sampler's glUniform1i clears it; one
        that failed is, at the next call that has Mesa decide whether draws
        are valid). The draws themselves keep Mesa's last decision
        (DrawCalls.revalidate): this call is not one that decides."""
        v = dict(args).get("pipeline", a[0] if a else None)
        pipe = self.pipeline(no, name, v)
        if pipe is None:
            return   # GL_INVALID_OPERATION: no such pipeline
        bound, used = self.s.pipeline, self.s.program
        self.s.pipeline, self.s.program = v, 0   # (its stages, as if bound with no program in use)
        try:
            pipe.validated = self.pipeline_fault(pipe) is None
        finally:
            self.s.pipeline, self.s.program = bound, used

    def release_deleted_pipeline(self):
        """The pipeline deleted while bound (h_delete_pipelines) is current
        no more: its programs may go out of use."""
        old, self.s.pipeline = self.s.pipeline, 0
        for prog in set(self.s.pipelines.pop(old).stages.values()):
            self.out_of_use(prog)

    def h_delete_pipelines(self, no, name, a, args):
        for v in dict(args).get("pipelines") or []:
            pipe = self.s.pipelines.pop(v, None) if isinstance(v, int) and not isinstance(v, bool) else None
            if pipe is None:
                continue
            if self.s.pipeline == v:
                if self.recording():
                    # Mesa unbinds it by glBindProgramPipeline(0), which is
                    # GL_INVALID_OPERATION while feedback records: the
                    # pipeline stays current, its name free, until another
                    # is bound (h_bind_pipeline).
                    self.s.pipeline = ("deleted", v)
                    self.s.pipelines[self.s.pipeline] = pipe
                    continue
                self.s.pipeline = 0
            for prog in set(pipe.stages.values()):
                self.out_of_use(prog)

    def h_use_program_stages(self, no, name, a, args):
        """glUseProgramStages: the stages named take the program's
        executables of those stages (none for a stage it lacks, or for
        program 0); bits GL does not define, a program that is not
        separable or whose last link failed, are errors that change nothing."""
        d = dict(args)
        pipe = self.pipeline(no, name, d.get("pipeline"))
        bits = d.get("stages")
        if isinstance(bits, (list, tuple)):
            if "GL_ALL_SHADER_BITS" in bits:
                stages = set(STAGE_BIT_VALUES.values())
            elif all(b in STAGE_BITS for b in bits):
                stages = {STAGE_BITS[b] for b in bits}
            else:
                return   # GL_INVALID_VALUE
        elif isinstance(bits, int) and not isinstance(bits, bool):
            if bits & 0xFFFFFFFF == 0xFFFFFFFF:
                stages = set(STAGE_BIT_VALUES.values())
            elif bits & ~0x3F:
                return   # GL_INVALID_VALUE
            else:
                stages = {s for bit, s in STAGE_BIT_VALUES.items() if bits & bit}
        elif bits == "GL_ALL_SHADER_BITS" or bits in STAGE_BITS:
            stages = set(STAGE_BIT_VALUES.values()) if bits == "GL_ALL_SHADER_BITS" else {STAGE_BITS[bits]}
        else:
            fail_call(no, f"{printable(name)}: stages {printable(bits)} are no bitfield")
        if pipe is None:
            return   # GL_INVALID_OPERATION: no such pipeline
        if self.recording() and not self.s.program and self.s.pipeline == d.get("pipeline"):
            return   # GL_INVALID_OPERATION: the pipeline draws run, while transform feedback records
        v = d.get("program")
        p = None
        if v:
            p = self.s.programs.get(name_arg(no, name, v, "program"))
            if p is None or p.linked is None or not p.separable or \
                    ("vertex" in p.linked[0] and not self.vertex_stage().links(p)):
                return   # GL_INVALID_VALUE or GL_INVALID_OPERATION: the stages stay as they were
        old = set(pipe.stages.values())
        pipe.validated = False
        for stage in stages:
            if p is not None and stage in p.linked[0]:
                pipe.stages[stage] = v
            else:
                pipe.stages.pop(stage, None)
        for prog in old - set(pipe.stages.values()):
            self.out_of_use(prog)
        if pipe is self.current_pipeline():
            self.revalidate()   # (Mesa decides again for the pipeline draws run, not another)

    def h_active_shader_program(self, no, name, a, args):
        d = dict(args)
        pipe = self.pipeline(no, name, d.get("pipeline"))
        v = d.get("program")
        if pipe is None:
            return
        if v != 0:
            p = self.s.programs.get(name_arg(no, name, v, "program"))
            if p is None or p.linked is None:
                return   # GL_INVALID_OPERATION
        pipe.active = v
        if pipe is self.current_pipeline():
            self.revalidate()   # (as glUseProgramStages)

    def current_pipeline(self):
        """The pipeline draws run: the bound one when no program is in use
        (Mesa's ctx->_Shader when it is a pipeline object), else None."""
        return None if self.s.program in self.s.programs else self.s.pipelines.get(self.s.pipeline)

    def h_transform_feedback_varyings(self, no, name, a, args):
        """The outputs a program's next link records by transform feedback
        (the capture's own, updating particles, say): what they write into
        buffers is GPU work (glstate.feedback), and the link may fail on
        them, as Mesa decides (vertex_stage.full_link)."""
        d = dict(args)
        count = checked(no, integer, d.get("count"), f"{name}: the count", *I32)
        names, mode = d.get("varyings"), enum_arg(d.get("bufferMode"), no, f"{name}: the buffer mode")
        if count < 0 or mode not in ("GL_INTERLEAVED_ATTRIBS", "GL_SEPARATE_ATTRIBS") or self.s.feedback[1]:
            return   # GL_INVALID_VALUE, GL_INVALID_ENUM, or _OPERATION while active: the call changes nothing
        if count and not (isinstance(names, list) and len(names) >= count and
                          all(isinstance(v, str) for v in names[:count])):
            fail_call(no, f"{printable(name)}: the capture does not hold its {count} output names")
        if count > MAX_FEEDBACK_VARYINGS:
            fail_call(no, f"{printable(name)}: {count} outputs, more than {MAX_FEEDBACK_VARYINGS} (docs/gl-capture.md)")
        self.program(no, name, d.get("program")).feedback_next = (tuple(names[:count]), mode) if count else None

    def h_uniform_subroutines(self, no, name, a, args):
        """Subroutine choices of a fragment shader cannot move a vertex; of a
        stage that can, they are not emulated."""
        if dict(args).get("shadertype") != "GL_FRAGMENT_SHADER":
            fail_call(no, f"{printable(name)}: shader subroutines before the fragment stage are not emulated")

    HANDLERS = {
        "glCreateShader": h_create_shader,
        "glShaderSource": h_shader_source,
        "glCompileShader": h_compile_shader,
        "glCreateProgram": h_create_program,
        "glAttachShader": h_attach_shader,
        "glDetachShader": h_attach_shader,
        "glBindAttribLocation": h_bind_attrib_location,
        "glLinkProgram": h_link_program,
        "glUseProgram": h_use_program,
        "glUseProgramObject": h_use_program,
        "glDeleteProgram": h_delete_program,
        "glGetUniformLocation": h_get_uniform_location,
        "glGetUniformBlockIndex": h_get_uniform_block_index,
        "glGetActiveUniformBlockName": h_get_block_name,
        "glGetProgramResourceName": h_get_block_name,
        "glUniformBlockBinding": h_uniform_block_binding,
        "glGetProgramResourceLocation": h_get_program_resource,
        "glGetProgramResourceIndex": h_get_program_resource,
        "glUniformSubroutinesuiv": h_uniform_subroutines,
        "glProgramParameteri": h_program_parameter,
        "glPatchParameteri": h_patch_parameter,
        "glPatchParameterfv": h_patch_parameter,
        "glCreateShaderProgramv": h_create_shader_program,
        "glGenProgramPipelines": h_gen_pipelines,
        "glCreateProgramPipelines": h_gen_pipelines,
        "glBindProgramPipeline": h_bind_pipeline,
        "glValidateProgramPipeline": h_validate_pipeline,
        "glDeleteProgramPipelines": h_delete_pipelines,
        "glUseProgramStages": h_use_program_stages,
        "glActiveShaderProgram": h_active_shader_program,
        "glTransformFeedbackVaryings": h_transform_feedback_varyings,
    } | dict.fromkeys([f"gl{p}Uniform{n}{t}{v}" for p in ("", "Program") for n in "1234"
                      for t in ("f", "i", "ui", "d") for v in ("", "v")]
                     + [f"gl{p}UniformMatrix{s}{t}v" for p in ("", "Program")
                        for s in ("2", "3", "4", "2x3", "3x2", "2x4", "4x2", "3x4", "4x3") for t in ("f", "d")],
                     h_uniform)

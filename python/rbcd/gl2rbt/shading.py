"""What a draw's fragment shader costs the GPU (docs/gpu-model.md, "Shading
cost"): counted on the fragment shader as Mesa compiles it.

Mesa prints every shader it compiles, in its final NIR form, when MESA_GLSL
says `dump` (a release build does too); the count is taken in a child process
of its own (the print goes to that process's standard error, and Mesa's
shader cache is off there so that every program is compiled and printed).
Per program, from its fragment shader's NIR:

    alu   scalar ALU instructions (NIR is scalar: a vec4 multiply is four)
    tex   texture instructions (tex, txb, txl, txd, txf, txf_ms, tg4, ...)

    cost  = alu + 4 x tex                      (in reference cycles)
    shade = 100 x cost / 8                     (percent, 1 to 10000)

The reference is gpu.cycles_per_fragment (8): the fixed-function textured
fragment, one texture fetch modulated by the colour (1 tex, 4 fmul) costs 8,
so its shade is 100 and a trace without shading costs means exactly that
fragment everywhere. Every instruction is counted once, whichever branch it
sits in; a loop's body once. Moves, constants, variable loads and stores, and
the vector constructors NIR needs between scalar instructions are not work
of a fragment processor and are not counted."""
import json
import os
import re
import subprocess
import sys

REFERENCE_CYCLES = 8
TEX_CYCLES = 4
SHADE_MIN, SHADE_MAX = 1, 10000

TEX_OPS = {"tex", "txb", "txl", "txd", "txf", "txf_ms", "txf_ms_fb", "txf_ms_mcs", "txs", "lod", "tg4",
           "query_levels", "texture_samples", "samples_identical", "tex_prefetch", "fragment_fetch",
           "fragment_mask_fetch"}
# What NIR prints between instructions that a processor does not execute as
# work of its own.
NOT_WORK = {"load_const", "deref_var", "deref_array", "deref_struct", "deref_cast", "intrinsic", "phi",
            "undefined", "mov", "vec2", "vec3", "vec4", "vec5", "vec8", "vec16"}
# "vec4 32 ssa_9 = (float32)tex ssa_8 (coord), ..." / "vec1 32 ssa_10 = fmul ssa_5, ssa_0"
INSTR = re.compile(r"^\s*vec\d+ \d+ ssa_\d+ = (?:\([a-z0-9]+\))?([a-z_0-9]+)\b")
CHILD_TIMEOUT = 120


def shade_percent(alu, tex):
    cost = alu + TEX_CYCLES * tex
    return max(SHADE_MIN, min(SHADE_MAX, round(100 * cost / REFERENCE_CYCLES)))


def count_fragment_nir(dump):
    """(alu, tex) of the last fragment shader in a MESA_GLSL=dump print, or
    None when it holds none."""
    sections = re.split(r"^shader: ", dump, flags=re.M)
    fragment = [s for s in sections if s.startswith("MESA_SHADER_FRAGMENT")]
    if not fragment:
        return None
    alu = tex = 0
    for line in fragment[-1].splitlines():
        m = INSTR.match(line)
        if not m:
            continue
        op = m.group(1)
        if op in TEX_OPS:
            tex += 1
        elif op not in NOT_WORK:
            alu += 1
    return alu, tex


class ShadingCosts:
    """Each linked program's shade, measured once (by the digest of its
    sources) in one child Mesa for the whole conversion; None for a program
    Mesa does not link there, or without a fragment shader (its draws then
    carry no cost)."""

    def __init__(self, es=False):
        self.es = es
        self.known = {}
        self.child = None

    def shade_of(self, digest, sources):
        if digest not in self.known:
            self.known[digest] = self.measure(sources) if "fragment" in sources else None
        return self.known[digest]

    def start(self):
        env = dict(os.environ, MESA_GLSL="dump", MESA_SHADER_CACHE_DISABLE="true")
        pkg = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
        env["PYTHONPATH"] = pkg + (os.pathsep + env["PYTHONPATH"] if env.get("PYTHONPATH") else "")
        self.child = subprocess.Popen([sys.executable, "-m", "rbcd.gl2rbt.shading", "--es" if self.es else "--gl"],
                                      env=env, stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                                      stderr=subprocess.PIPE)

    def measure(self, sources):
        """One program through the child: a JSON line in; Mesa's print up to
        END_MARK on standard error, then the link status on standard output."""
        try:
            if self.child is None:
                self.start()
            self.child.stdin.write(json.dumps(sources).encode() + b"\n")
            self.child.stdin.flush()
            # Its print first (it comes first, and may be longer than a pipe holds).
            dump = []
            for line in self.child.stderr:
                if line == END_MARK:
                    break
                dump.append(line)
            status = self.child.stdout.readline()
        except (OSError, ValueError):
            self.close()
            return None
        if status.strip() != b"linked":
            return None
        counted = count_fragment_nir(b"".join(dump).decode("utf-8", "replace"))
        return None if counted is None else shade_percent(*counted)

    def close(self):
        if self.child is not None:
            self.child.kill()
            self.child.wait()
            self.child = None


END_MARK = b"@@rbcd-shading-end\n"


def _serve(es):
    """The child: links each program whose stages' sources come as a JSON
    line on standard input, in a context like the converter's; Mesa prints
    it on standard error, END_MARK follows there, and then `linked` or
    `failed` on standard output."""
    from .glstate.programs import STAGES
    from .mesa import Mesa
    gl_stage = {stage: gl_name for gl_name, stage in STAGES.items()}
    gl = Mesa(es=es).gl
    for line in sys.stdin.buffer:
        ok = False
        try:
            prog = gl.glCreateProgram()
            for stage, src in json.loads(line).items():
                sh = gl.glCreateShader(getattr(gl, gl_stage[stage]))
                gl.glShaderSource(sh, src)
                gl.glCompileShader(sh)
                gl.glAttachShader(prog, sh)
            gl.glLinkProgram(prog)
            ok = bool(gl.glGetProgramiv(prog, gl.GL_LINK_STATUS))
        except Exception:   # the parent reads only the status: no cost for this program
            ok = False
        sys.stderr.flush()
        os.write(2, END_MARK)
        sys.stdout.write("linked\n" if ok else "failed\n")
        sys.stdout.flush()


if __name__ == "__main__":
    _serve(sys.argv[1:] == ["--es"])

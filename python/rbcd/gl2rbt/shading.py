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
import ctypes
import json
import os
import re
import select
import signal
import subprocess
import sys
import time

from .errors import ConvertError
from .mesa import MESA_GROWTH, MESA_SECONDS, MESA_WALL_SECONDS, over_time

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
# The child's work for one program (Mesa compiling and linking it, and
# printing it) is bounded as the main process's Mesa work is (mesa.Watchdog;
# docs/gl-capture.md, limits): the time from the program sent to its status
# read (the child's processor time, and the wall clock's at ten times it),
# and the resident memory the child added meanwhile, checked every 0.1 s.
CHILD_SECONDS = MESA_SECONDS
CHILD_WALL_SECONDS = MESA_WALL_SECONDS
CHILD_GROWTH = MESA_GROWTH
# What of a line of Mesa's print is kept: an instruction's opcode comes first.
LINE_KEPT = 4096
PR_SET_PDEATHSIG = 1

# The children running, each stopped by stop_children (rbcd-gl2rbt's
# clean-up, however the run ends) if its ShadingCosts has not closed it.
_children = set()


def shade_percent(alu, tex):
    cost = alu + TEX_CYCLES * tex
    return max(SHADE_MIN, min(SHADE_MAX, round(100 * cost / REFERENCE_CYCLES)))


def count_fragment_nir(dump):
    """(alu, tex) of the last fragment shader in a MESA_GLSL=dump print, or
    None when it holds none."""
    count = FragmentCount()
    count.feed(dump.encode("utf-8") + b"\n")
    return count.result()


class FragmentCount:
    """count_fragment_nir over Mesa's print as it comes, a piece at a time,
    in memory bounded whatever the print holds (a line's first LINE_KEPT
    bytes are read, and the counts of the last fragment shader kept);
    `ended` once END_MARK's line has come."""

    def __init__(self):
        self.head = b""          # the line being read, its first LINE_KEPT bytes
        self.current = None      # (alu, tex) of the fragment shader being read, or None
        self.last = None         # of the last fragment shader read whole
        self.ended = False

    def feed(self, data):
        start = 0
        while start < len(data) and not self.ended:
            nl = data.find(b"\n", start)
            stop = len(data) if nl < 0 else nl
            if len(self.head) < LINE_KEPT:
                self.head += data[start:min(stop, start + LINE_KEPT - len(self.head))]
            if nl < 0:
                return
            self.line(self.head.decode("utf-8", "replace"))
            self.head = b""
            start = nl + 1

    def line(self, text):
        if text == END_LINE:
            self.ended = True
        elif text.startswith("shader: "):
            if self.current is not None:
                self.last = self.current
            self.current = [0, 0] if text.startswith("shader: MESA_SHADER_FRAGMENT") else None
        elif self.current is not None:
            m = INSTR.match(text)
            if m:
                op = m.group(1)
                if op in TEX_OPS:
                    self.current[1] += 1
                elif op not in NOT_WORK:
                    self.current[0] += 1

    def result(self):
        counted = self.current if self.current is not None else self.last
        return None if counted is None else tuple(counted)


def processor_seconds(pid):
    """The processor time a process has spent, all its threads (0 once it is gone)."""
    try:
        with open(f"/proc/{pid}/stat") as f:
            fields = f.read().rsplit(")", 1)[1].split()
        return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")   # utime, stime
    except (OSError, ValueError, IndexError):
        return 0.0


def resident_bytes(pid):
    """A process's resident memory (0 once it is gone)."""
    try:
        with open(f"/proc/{pid}/statm") as f:
            return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE")
    except (OSError, ValueError, IndexError):
        return 0


class ShadingCosts:
    """Each linked program's shade, measured once (by the digest of its
    sources) in one child Mesa for the whole conversion; None for a program
    Mesa does not link there, or without a fragment shader (its draws then
    carry no cost). The child's work for a program is bounded (CHILD_SECONDS,
    CHILD_GROWTH: the capture's error, naming the program), it is stopped
    when the run ends however it ends (stop_children), and it ends itself
    when the converter dies (PR_SET_PDEATHSIG)."""

    def __init__(self, es=False):
        self.es = es
        self.known = {}
        self.child = None

    def shade_of(self, digest, sources):
        if digest not in self.known:
            self.known[digest] = self.measure(digest, sources) if "fragment" in sources else None
        return self.known[digest]

    def start(self):
        env = dict(os.environ, MESA_GLSL="dump", MESA_SHADER_CACHE_DISABLE="true")
        pkg = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
        env["PYTHONPATH"] = pkg + (os.pathsep + env["PYTHONPATH"] if env.get("PYTHONPATH") else "")
        self.child = subprocess.Popen([sys.executable, "-m", "rbcd.gl2rbt.shading", "--es" if self.es else "--gl",
                                       str(os.getpid())],
                                      env=env, stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                                      stderr=subprocess.PIPE)
        _children.add(self.child)
        os.set_blocking(self.child.stdin.fileno(), False)

    def measure(self, digest, sources):
        """One program through the child: a JSON line in; Mesa's print up to
        END_MARK on standard error, then the link status on standard output."""
        what = f"program {digest[:8]} (its fragment shader's cost, measured by a Mesa of its own)"
        try:
            if self.child is None:
                self.start()
                # Mesa's start in the child is not the program's work.
                if self.exchange(b"", None, what) != b"ready":
                    self.close()
                    return None
            count = FragmentCount()
            status = self.exchange(json.dumps(sources).encode() + b"\n", count, what)
        except BaseException:   # an interruption too: the child goes with the run
            self.close()
            raise
        if status is None:   # the child is gone (Mesa crashed on the program): no cost
            self.close()
            return None
        if status != b"linked":
            return None
        counted = count.result()
        return None if counted is None else shade_percent(*counted)

    def exchange(self, payload, count, what):
        """Writes `payload` to the child, reads its standard error into
        `count` up to END_MARK (None: read and passed over) and a line from
        its standard output: that line, or None when the child is gone."""
        child = self.child
        fin, fout, ferr = child.stdin.fileno(), child.stdout.fileno(), child.stderr.fileno()
        t0, cpu0, rss0 = time.monotonic(), processor_seconds(child.pid), resident_bytes(child.pid)
        sent, out = 0, b""
        while b"\n" not in out or (count is not None and not count.ended):
            readers = [ferr] + ([fout] if b"\n" not in out else [])
            writers = [fin] if sent < len(payload) else []
            ready_r, ready_w, _ = select.select(readers, writers, [], 0.1)
            if ready_w:
                try:
                    sent += os.write(fin, payload[sent:sent + 65536])
                except BlockingIOError:
                    pass
                except OSError:
                    return None
            for fd in ready_r:
                data = os.read(fd, 65536)
                if not data:
                    return None
                if fd == fout:
                    out += data
                    if len(out) > 64:   # the child writes one word
                        return None
                elif count is not None:
                    count.feed(data)
            why = over_time(t0, cpu0, time.monotonic(), processor_seconds(child.pid), CHILD_SECONDS,
                            CHILD_WALL_SECONDS)
            if why:
                self.fail(what, why)
            if resident_bytes(child.pid) - rss0 > CHILD_GROWTH:
                self.fail(what, f"Mesa took more than {CHILD_GROWTH >> 20} MiB of memory for it")
        return out.split(b"\n", 1)[0]

    def fail(self, what, why):
        self.close()
        raise ConvertError(f"{what}: {why} (docs/gl-capture.md, limits)")

    def close(self):
        if self.child is not None:
            stop_child(self.child)
            self.child = None


def stop_child(child):
    _children.discard(child)
    if child.poll() is None:
        child.kill()
    child.wait()
    for f in (child.stdin, child.stdout, child.stderr):
        try:
            f.close()
        except OSError:
            pass


def stop_children():
    """Stops every child still running (rbcd-gl2rbt's end, however it ends)."""
    for child in list(_children):
        stop_child(child)


END_MARK = b"@@rbcd-shading-end\n"
END_LINE = END_MARK.decode().strip()


def die_with(parent):
    """The child ends when the converter does, however it ends (killed
    outright too: its clean-up then never runs): PR_SET_PDEATHSIG, and the
    converter already gone before it was set."""
    try:
        ctypes.CDLL(None, use_errno=True).prctl(PR_SET_PDEATHSIG, signal.SIGKILL, 0, 0, 0)
    except (OSError, AttributeError):
        pass
    if os.getppid() != parent:
        os._exit(0)


def _serve(es, parent):
    """The child: links each program whose stages' sources come as a JSON
    line on standard input, in a context like the converter's; Mesa prints
    it on standard error, END_MARK follows there on a line of its own, and
    then `linked` or `failed` on standard output (`ready` there first, once
    Mesa has started)."""
    die_with(parent)
    # Ctrl-C reaches the whole process group: the converter ends the child.
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    from .glstate.programs import STAGES
    from .mesa import Mesa
    gl_stage = {stage: gl_name for gl_name, stage in STAGES.items()}
    mesa = Mesa(es=es)
    gl = mesa.gl
    sys.stdout.write("ready\n")
    sys.stdout.flush()
    for line in sys.stdin.buffer:
        ok = False
        prog, shaders = None, []
        try:
            prog = gl.glCreateProgram()
            stages = json.loads(line)
            for stage, src in stages.items():
                sh = gl.glCreateShader(getattr(gl, gl_stage[stage]))
                shaders.append(sh)
                gl.glShaderSource(sh, src)
                gl.glCompileShader(sh)
                gl.glAttachShader(prog, sh)
            if "vertex" not in stages:   # a pipeline's fragment program: OpenGL ES links it only separable
                mesa.separable(prog)
            gl.glLinkProgram(prog)
            ok = bool(gl.glGetProgramiv(prog, gl.GL_LINK_STATUS))
        except Exception:   # the parent reads only the status: no cost for this program
            ok = False
        try:   # measured once: Mesa's memory for it goes
            for sh in shaders:
                gl.glDeleteShader(sh)
            if prog is not None:
                gl.glDeleteProgram(prog)
        except Exception:   # noqa: BLE001: kept, then, as it had always been
            pass
        sys.stderr.flush()
        os.write(2, b"\n" + END_MARK)   # Mesa's last line may lack its newline
        sys.stdout.write("linked\n" if ok else "failed\n")
        sys.stdout.flush()


if __name__ == "__main__":
    if len(sys.argv) != 3 or sys.argv[1] not in ("--es", "--gl") or not sys.argv[2].isdigit():
        sys.exit("usage: python3 -m rbcd.gl2rbt.shading --es|--gl PARENT_PID (rbcd-gl2rbt's child)")
    _serve(sys.argv[1] == "--es", int(sys.argv[2]))

"""A draw's shading cost from its fragment shader as Mesa compiles it
(rbcd.gl2rbt.shading; docs/gpu-model.md, "Shading cost")."""
import os
import signal
import subprocess
import sys
import threading
import time

import pytest

from gl_captures import alive
from rbcd.gl2rbt import shading
from rbcd.gl2rbt.errors import ConvertError
from rbcd.gl2rbt.shading import END_MARK, FragmentCount, ShadingCosts, count_fragment_nir, shade_percent

# What Mesa prints for a linked program under MESA_GLSL=dump, cut to the
# lines the count reads: a vertex shader, then the fragment shader.
NIR = """shader: MESA_SHADER_VERTEX
impl main {
	vec1 32 ssa_3 = fmul ssa_1, ssa_2
}
shader: MESA_SHADER_FRAGMENT
name: GLSL1
impl main {
	block block_0:
	vec1 32 ssa_0 = load_const (0x40000000 = 2.000000)
	vec1 32 ssa_4 = deref_var &uv (shader_in float)
	vec1 32 ssa_5 = intrinsic load_deref (ssa_4) (access=0)
	vec2 32 ssa_8 = vec2 ssa_5, ssa_7
	vec4 32 ssa_9 = (float32)tex ssa_8 (coord), 0 (texture), 0 (sampler)
	vec1 32 ssa_10 = fmul ssa_5, ssa_0
	vec4 32 ssa_13 = (float32)txl ssa_12 (coord), ssa_0 (lod), 0 (texture), 0 (sampler)
	vec1 32 ssa_18 = flt32 ssa_1, ssa_14
	if ssa_18 {
		vec1 32 ssa_21 = fadd ssa_14, ssa_20.x
	}
	vec1 32 ssa_25 = phi block_1: ssa_21, block_2: ssa_14
	vec1 32 ssa_26 = mov ssa_25
}
"""


def test_the_count_reads_the_fragment_shader_only():
    # fmul, flt32, fadd: 3 ALU; tex, txl: 2 texture; loads, constants,
    # constructors, phi and mov are not counted; the vertex shader's fmul neither.
    assert count_fragment_nir(NIR) == (3, 2)
    assert count_fragment_nir("shader: MESA_SHADER_VERTEX\n\tvec1 32 ssa_3 = fmul ssa_1, ssa_2\n") is None


def test_the_count_reads_the_print_as_it_comes():
    """The child's print is read a piece at a time (one byte here): the same
    count, and its end seen on END_MARK's own line; a line longer than the
    part of it read costs no more memory."""
    count = FragmentCount()
    data = NIR.encode() + b"\n" + END_MARK
    for i in range(len(data)):
        count.feed(data[i:i + 1])
    assert count.ended and count.result() == (3, 2)
    count = FragmentCount()
    count.feed(b"shader: MESA_SHADER_FRAGMENT\n\tvec1 32 ssa_1 = fadd ssa_0, ssa_0 " + b"x" * 10 ** 6 + b"\n")
    count.feed(b"\tvec1 32 ssa_2 = fmul ssa_1, ssa_1\n" + END_MARK)
    assert count.ended and count.result() == (2, 0) and len(count.head) == 0


def test_the_reference_fragment_is_100_and_the_range_is_bounded():
    assert shade_percent(4, 1) == 100, "four multiplies and one fetch: gpu.cycles_per_fragment"
    assert shade_percent(3, 2) == 138
    assert shade_percent(0, 0) == 1
    assert shade_percent(10 ** 6, 0) == 10000


VS = "#version 330\nin vec4 p; out vec2 uv; void main() { uv = p.xy; gl_Position = p; }\n"
ONE = ("#version 330\nuniform sampler2D t; in vec2 uv; out vec4 c;\n"
       "void main() { c = texture(t, uv) * vec4(uv, uv); }\n")
THREE = ("#version 330\nuniform sampler2D t, u, v; in vec2 uv; out vec4 c;\n"
         "void main() { c = texture(t, uv) * texture(u, uv * 2.0) + texture(v, uv.yx); }\n")


def test_mesa_measures_each_program_once():
    pytest.importorskip("OpenGL", reason="python3-opengl is missing (scripts/setup.sh --gl installs it)")
    costs = ShadingCosts()
    try:
        one = costs.shade_of("one", {"vertex": VS, "fragment": ONE})
        if one is None:
            pytest.skip("Mesa's surfaceless EGL gives no context here (scripts/setup.sh --gl)")
        assert one == 100, "one fetch and four multiplies"
        three = costs.shade_of("three", {"vertex": VS, "fragment": THREE})
        assert three == shade_percent(10, 3), "three fetches, four multiplies, four adds, uv * 2.0"
        assert costs.shade_of("broken", {"vertex": VS, "fragment": "not glsl"}) is None
        assert costs.shade_of("vertex only", {"vertex": VS}) is None
        assert costs.shade_of("one", {}) == 100, "known by its digest: not linked again"
    finally:
        costs.close()


# A fragment shader Mesa takes seconds and hundreds of MB on (a switch of
# 600 cases: 7 s and 210 MB in the child, printing its NIR): past either
# bound the measure is the capture's error, naming the program, and the
# child is stopped.
SWITCH = ("#version 330\nin vec2 uv; out vec4 c;\nvoid main() { int sw = int(uv.x); float t = 0.0; switch (sw) {"
          + "".join(f"case {i}: t = {i}.0; break;" for i in range(600)) + "} c = vec4(t); }\n")



@pytest.mark.parametrize("bound, value, words", [("CHILD_SECONDS", 1, "Mesa worked on it for more than 1 s"),
                                                 ("CHILD_GROWTH", 48 << 20, "Mesa took more than 48 MiB")],
                         ids=["time", "memory"])
def test_the_childs_work_for_a_program_is_bounded(monkeypatch, bound, value, words):
    """The child's Mesa had no bound (a 4,000-case switch: 686 MB, and
    more than 30 s): it has the main process's (mesa.MESA_SECONDS,
    MESA_GROWTH), lowered here."""
    pytest.importorskip("OpenGL", reason="python3-opengl is missing (scripts/setup.sh --gl installs it)")
    costs = ShadingCosts()
    try:
        if costs.shade_of("one", {"vertex": VS, "fragment": ONE}) is None:
            pytest.skip("Mesa's surfaceless EGL gives no context here (scripts/setup.sh --gl)")
        child = costs.child.pid
        monkeypatch.setattr(shading, bound, value)
        t = time.monotonic()
        with pytest.raises(ConvertError) as e:
            costs.shade_of("5e1fc0de" * 8, {"vertex": VS, "fragment": SWITCH})
        # The bound, not the switch's own end, stopped it (the switch alone
        # takes the child longer; a loose figure: the machine may be busy).
        assert time.monotonic() - t < 25
        assert str(e.value).startswith("program 5e1fc0de (its fragment shader's cost") and words in str(e.value) \
            and str(e.value).endswith("(docs/gl-capture.md, limits)"), e.value
        assert costs.child is None and not alive(child)
    finally:
        costs.close()


def signal_if_alive(pid, sig):
    try:
        os.kill(pid, sig)
    except ProcessLookupError:
        pass


@pytest.mark.parametrize("wall, words", [(60, None), (1, "Mesa took more than 1 s on it")], ids=["cpu", "wall"])
def test_the_childs_time_is_its_processor_time(monkeypatch, wall, words):
    """A busy machine does not stretch the child's bound: its processor
    time is measured, not the wall clock's (held stopped for 2.5 s, the
    child used none: under a 1 s bound the program's cost still comes
    back; a wall-clock bound had refused good captures beside other work),
    and the wall clock bounds a child that waits (CHILD_WALL_SECONDS)."""
    pytest.importorskip("OpenGL", reason="python3-opengl is missing (scripts/setup.sh --gl installs it)")
    costs, resume = ShadingCosts(), None
    try:
        if costs.shade_of("one", {"vertex": VS, "fragment": ONE}) is None:
            pytest.skip("Mesa's surfaceless EGL gives no context here (scripts/setup.sh --gl)")
        monkeypatch.setattr(shading, "CHILD_SECONDS", 1)
        monkeypatch.setattr(shading, "CHILD_WALL_SECONDS", wall)
        child = costs.child.pid
        os.kill(child, signal.SIGSTOP)
        resume = threading.Timer(2.5, signal_if_alive, (child, signal.SIGCONT))
        resume.start()
        other = ONE.replace("c = ", "c = 0.5 * ")
        if words is None:
            assert costs.shade_of("two", {"vertex": VS, "fragment": other}) > 0
        else:
            with pytest.raises(ConvertError) as e:
                costs.shade_of("5e1fc0de" * 8, {"vertex": VS, "fragment": other})
            assert words in str(e.value), e.value
    finally:
        costs.close()
        if resume is not None:
            resume.join()


PARENT = """import os, sys, threading
from rbcd.gl2rbt.shading import ShadingCosts
costs = ShadingCosts()
costs.shade_of("one", {"vertex": sys.argv[1], "fragment": sys.argv[2]})
print(costs.child.pid, flush=True)
costs.shade_of("switch", {"vertex": sys.argv[1], "fragment": sys.argv[3]})
"""


@pytest.mark.parametrize("how", ["killed", "stop_children"])
def test_the_child_ends_with_the_converter(how):
    """The child went on compiling after the converter was gone (seen at
    370 MB seconds later): killed outright, the converter takes it along
    (PR_SET_PDEATHSIG); ending as it does, stop_children stops it."""
    pytest.importorskip("OpenGL", reason="python3-opengl is missing (scripts/setup.sh --gl installs it)")
    if how == "killed":
        env = dict(os.environ, PYTHONPATH=os.pathsep.join(sys.path))
        p = subprocess.Popen([sys.executable, "-c", PARENT, VS, ONE, SWITCH], stdout=subprocess.PIPE, env=env,
                             text=True)
        try:
            child = int(p.stdout.readline() or 0)
            if not child:
                pytest.skip("Mesa's surfaceless EGL gives no context here (scripts/setup.sh --gl)")
            time.sleep(1)   # at work on the switch
            assert alive(child)
        finally:
            p.kill()
            p.wait()
    else:
        costs = ShadingCosts()
        if costs.shade_of("one", {"vertex": VS, "fragment": ONE}) is None:
            pytest.skip("Mesa's surfaceless EGL gives no context here (scripts/setup.sh --gl)")
        child = costs.child.pid
        shading.stop_children()
        assert not shading._children
    t = time.monotonic()
    while alive(child) and time.monotonic() - t < 3:
        time.sleep(0.05)
    assert not alive(child), f"the child ({child}) outlives its converter"

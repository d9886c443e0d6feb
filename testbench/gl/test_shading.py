"""A draw's shading cost from its fragment shader as Mesa compiles it
(rbcd.gl2rbt.shading; docs/gpu-model.md, "Shading cost")."""
import pytest

from rbcd.gl2rbt.shading import ShadingCosts, count_fragment_nir, shade_percent

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

"""rbcd.gl2rbt.glmath: fixed-function matrices and primitive assembly, against
GL's definitions (OpenGL 2.1 specification, 2.11 and 2.6.1), without Xvfb or
apitrace."""
import math
import random

import pytest

np = pytest.importorskip("numpy", reason="python3-numpy is missing (scripts/setup.sh --gl installs it)")
from rbcd.gl2rbt import glmath  # noqa: E402


def ndc(m, p):
    c = m @ np.array([*p, 1.0])
    return c[:3] / c[3]


def test_mat_mul_is_the_fixed_order_sum():
    # The game suite's checksums need the same bytes on every machine: each
    # element is ((a0*b0 + a1*b1) + a2*b2) + a3*b3, in IEEE double.
    rng = random.Random(7)
    for _ in range(200):
        a = np.array([[rng.uniform(-1e3, 1e3) for _ in range(4)] for _ in range(4)])
        b = np.array([[rng.uniform(-1e3, 1e3) for _ in range(4)] for _ in range(4)])
        r = glmath.mat_mul(a, b)
        for i in range(4):
            for j in range(4):
                want = a[i, 0] * b[0, j]
                for k in range(1, 4):
                    want = want + a[i, k] * b[k, j]
                assert r[i, j] == want, f"element ({i}, {j}) of a product"


def test_mat_mul_takes_vertex_rows():
    pos = np.array([[1.0, 2.0, 3.0, 1.0], [4.0, 5.0, 6.0, 1.0]])
    m = glmath.mat_translate(10, 20, 30)
    assert glmath.mat_mul(pos, m.T).tolist() == [[11, 22, 33, 1], [14, 25, 36, 1]]


def test_rotate_is_glrotate():
    r = glmath.mat_rotate(90, 0, 0, 2)   # the axis is normalized
    assert np.allclose(r @ [1, 0, 0, 1], [0, 1, 0, 1]), "90 degrees about z takes x to y"
    assert np.allclose(r[:3, :3] @ r[:3, :3].T, np.identity(3)), "a rotation is orthonormal"
    assert glmath.mat_rotate(30, 0, 0, 0).tolist() == np.identity(4).tolist(), "a zero axis is no rotation"
    r = glmath.mat_rotate(-45, 1, 1, 0)
    assert np.allclose(r @ [1, 1, 0, 1], [1, 1, 0, 1]), "the axis is fixed"


def test_scale_and_translate():
    assert np.allclose(glmath.mat_scale(2, 3, 4) @ [1, 1, 1, 1], [2, 3, 4, 1])
    assert np.allclose(glmath.mat_translate(1, 2, 3) @ [0, 0, 0, 1], [1, 2, 3, 1])


def test_ortho_maps_its_box_to_the_cube():
    m = glmath.mat_ortho(0, 128, 0, 96, -100, 100)
    assert np.allclose(ndc(m, (0, 0, 100)), [-1, -1, -1]), "(l, b, -n) is the near corner"
    assert np.allclose(ndc(m, (128, 96, -100)), [1, 1, 1]), "(r, t, -f) is the far corner"
    assert np.allclose(ndc(m, (64, 48, -10)), [0, 0, 0.1])


def test_frustum_maps_near_and_far_planes():
    n, f = 1.0, 10.0
    m = glmath.mat_frustum(-1, 2, -0.5, 1.5, n, f)
    assert np.allclose(ndc(m, (-1, -0.5, -n)), [-1, -1, -1])
    assert np.allclose(ndc(m, (2, 1.5, -n)), [1, 1, -1])
    assert np.allclose(ndc(m, (2 * f / n, 1.5 * f / n, -f)), [1, 1, 1])
    assert m[3].tolist() == [0, 0, -1, 0], "w is the distance in front of the eye"
    assert math.isclose(ndc(m, (0, 0, -2 * n * f / (n + f)))[2], 0.0, abs_tol=1e-12)


@pytest.mark.parametrize("mode, n, want", [
    ("GL_TRIANGLES", 7, [[0, 1, 2], [3, 4, 5]]),
    # Odd triangles of a strip have their first two vertices swapped: every
    # triangle keeps the strip's winding.
    ("GL_TRIANGLE_STRIP", 5, [[0, 1, 2], [2, 1, 3], [2, 3, 4]]),
    ("GL_TRIANGLE_FAN", 5, [[0, 1, 2], [0, 2, 3], [0, 3, 4]]),
    ("GL_POLYGON", 4, [[0, 1, 2], [0, 2, 3]]),
    ("GL_QUADS", 9, [[0, 1, 2], [0, 2, 3], [4, 5, 6], [4, 6, 7]]),
    ("GL_QUAD_STRIP", 6, [[0, 1, 3], [0, 3, 2], [2, 3, 5], [2, 5, 4]]),
    ("GL_TRIANGLE_STRIP", 2, []),
    ("GL_TRIANGLE_FAN", 2, []),
    ("GL_QUAD_STRIP", 3, []),
    ("GL_LINES", 6, []),
], ids=lambda v: v.removeprefix("GL_").lower() if isinstance(v, str) else str(v) if isinstance(v, int) else "")
def test_triangle_assembly(mode, n, want):
    got = glmath.triangle_indices(mode, n)
    assert got.dtype == np.uint32 and got.shape[1:] == (3,)
    assert got.tolist() == want, f"{mode} of {n} vertices"

"""Fixed-function GL's matrices and primitive assembly, computed as a GL
implementation computes them (docs/gl-capture.md)."""
import math

import numpy as np



def mat_mul(a, b):
    """a @ b, as separate IEEE multiplies and adds in a fixed order. numpy's
    matmul goes to the BLAS, whose kernels (fused or not, summed in which
    order) depend on the machine: the converted traces of the game suite
    must be the same bytes everywhere (their checksums are recorded)."""
    r = a[:, 0:1] * b[0, :]
    for j in range(1, a.shape[1]):
        r = r + a[:, j:j + 1] * b[j, :]
    return r


def mat_translate(x, y, z):
    m = np.identity(4)
    m[0:3, 3] = (x, y, z)
    return m


def mat_scale(x, y, z):
    return np.diag([x, y, z, 1.0])


def mat_rotate(angle_deg, x, y, z):
    n = math.sqrt(x * x + y * y + z * z)
    m = np.identity(4)
    if n == 0.0:
        return m
    x, y, z = x / n, y / n, z / n
    a = math.radians(angle_deg)
    c, s = math.cos(a), math.sin(a)
    m[0:3, 0:3] = [[x * x * (1 - c) + c, x * y * (1 - c) - z * s, x * z * (1 - c) + y * s],
                   [y * x * (1 - c) + z * s, y * y * (1 - c) + c, y * z * (1 - c) - x * s],
                   [x * z * (1 - c) - y * s, y * z * (1 - c) + x * s, z * z * (1 - c) + c]]
    return m


def mat_ortho(l, r, b, t, n, f):
    m = np.identity(4)
    m[0, 0] = 2.0 / (r - l)
    m[1, 1] = 2.0 / (t - b)
    m[2, 2] = -2.0 / (f - n)
    m[0:3, 3] = (-(r + l) / (r - l), -(t + b) / (t - b), -(f + n) / (f - n))
    return m


def mat_frustum(l, r, b, t, n, f):
    m = np.zeros((4, 4))
    m[0, 0] = 2.0 * n / (r - l)
    m[1, 1] = 2.0 * n / (t - b)
    m[0, 2] = (r + l) / (r - l)
    m[1, 2] = (t + b) / (t - b)
    m[2, 2] = -(f + n) / (f - n)
    m[2, 3] = -2.0 * f * n / (f - n)
    m[3, 2] = -1.0
    return m


def triangle_indices(mode, n):
    """Vertex indices of the triangles GL assembles from n vertices in `mode`,
    keeping GL's winding (odd strip triangles swapped)."""
    if mode == "GL_TRIANGLES":
        k = n // 3
        return np.arange(3 * k, dtype=np.uint32).reshape(k, 3)
    if mode == "GL_TRIANGLE_STRIP":
        if n < 3:
            return np.zeros((0, 3), np.uint32)
        i = np.arange(n - 2, dtype=np.uint32)
        t = np.stack([i, i + 1, i + 2], axis=1)
        odd = (i % 2) == 1
        t[odd, 0], t[odd, 1] = i[odd] + 1, i[odd]
        return t
    if mode in ("GL_TRIANGLE_FAN", "GL_POLYGON"):
        if n < 3:
            return np.zeros((0, 3), np.uint32)
        i = np.arange(1, n - 1, dtype=np.uint32)
        return np.stack([np.zeros_like(i), i, i + 1], axis=1)
    if mode == "GL_TRIANGLES_ADJACENCY":
        # Each 6 vertices: a triangle of the 1st, 3rd and 5th, the others
        # its neighbours' (GL 4.6, 10.1.12), which only a geometry shader reads.
        k = n // 6
        return (np.arange(k, dtype=np.uint32)[:, None] * 6 + np.array([0, 2, 4], np.uint32)).reshape(k, 3)
    if mode == "GL_TRIANGLE_STRIP_ADJACENCY":
        # GL 4.6 table 10.1: triangle i of vertices 2i, 2i + 2, 2i + 4, the
        # first two swapped for odd i (a strip's winding).
        k = max(0, (n - 4) // 2)
        i = np.arange(k, dtype=np.uint32)
        t = np.stack([2 * i, 2 * i + 2, 2 * i + 4], axis=1)
        odd = (i % 2) == 1
        t[odd, 0], t[odd, 1] = 2 * i[odd] + 2, 2 * i[odd]
        return t
    if mode == "GL_QUADS":
        q = np.arange(n // 4, dtype=np.uint32) * 4
        return np.concatenate([np.stack([q, q + 1, q + 2], axis=1), np.stack([q, q + 2, q + 3], axis=1)]) \
            .reshape(2, -1, 3).transpose(1, 0, 2).reshape(-1, 3)
    if mode == "GL_QUAD_STRIP":
        k = max(0, (n - 2) // 2)
        q = np.arange(k, dtype=np.uint32) * 2
        return np.concatenate([np.stack([q, q + 1, q + 3], axis=1), np.stack([q, q + 3, q + 2], axis=1)]) \
            .reshape(2, -1, 3).transpose(1, 0, 2).reshape(-1, 3)
    return np.zeros((0, 3), np.uint32)

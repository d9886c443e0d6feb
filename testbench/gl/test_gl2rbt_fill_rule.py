"""Samples exactly on a triangle's edge: the converter gives them to the
triangle Mesa gives them to. GL leaves the rule to the implementation; Mesa
(llvmpipe) keeps samples on left and bottom edges, in GL's window
coordinates, in a window and a framebuffer object alike, while the scene
front end keeps left and top ones. A current attribute value a hair above
a pixel centre, snapped onto it, had moved a quad's covered rows by one
(98.44% against Mesa)."""
import struct

import numpy as np
import pytest

from gl_captures import Calls, gl2rbt_timed as gl2rbt, read_trace

pytest.importorskip("OpenGL", reason="python3-opengl is missing (scripts/setup.sh --gl)")

W, H = 64, 48

# Triangles in window coordinates (glOrtho over the window), every corner on
# a pixel centre, so every horizontal and vertical edge and the diagonals
# run through sample points: a square of two triangles in both windings,
# triangles with a horizontal top and a horizontal bottom edge, and one
# with a vertical right edge.
TRIANGLES = [
    [(4.5, 4.5), (20.5, 4.5), (20.5, 20.5)], [(4.5, 4.5), (20.5, 20.5), (4.5, 20.5)],
    [(24.5, 4.5), (24.5, 20.5), (40.5, 4.5)], [(24.5, 20.5), (40.5, 20.5), (40.5, 4.5)],
    [(44.5, 30.5), (60.5, 30.5), (52.5, 44.5)],
    [(44.5, 20.5), (52.5, 6.5), (60.5, 20.5)],
    [(4.5, 26.5), (30.5, 26.5), (30.5, 44.5)],
]


def vertices():
    return [(x, y, -10.0) for tri in TRIANGLES for x, y in tri]


def converted(tmp_path):
    data = b"".join(struct.pack("<3f", *v) for v in vertices())
    c = Calls(W, H)
    for i, first in enumerate(range(0, len(TRIANGLES) * 3, 3)):
        c.add("glPushDebugGroup", source="GL_DEBUG_SOURCE_APPLICATION", id=i + 1, length=-1, message="rbcd-object")
        c.add("glVertexPointer", size=3, type="GL_FLOAT", stride=0, pointer=data)
        c.add("glDrawArrays", mode="GL_TRIANGLES", first=first, count=3)
        c.add("glPopDebugGroup")
    c.swap()
    r = gl2rbt(tmp_path, c.write(tmp_path / "ties.xz"), "-o", tmp_path / "ties.rbt")
    assert r.returncode == 0, r.stderr
    frames, _ = read_trace(str(tmp_path / "ties.rbt"))
    covered = {}
    for (x, y), frags in frames[0].items():
        for _, obj, _, _ in frags:
            covered.setdefault(obj, set()).add((x, y))
    return covered


def drawn_by_mesa():
    """Each triangle drawn alone by Mesa into a framebuffer object of the
    window's size: the pixels it covers, rows counted down as in the trace."""
    from rbcd.gl2rbt.mesa import Mesa
    mesa = Mesa()
    GL = mesa.gl
    fbo, rb = GL.glGenFramebuffers(1), GL.glGenRenderbuffers(1)
    GL.glBindRenderbuffer(GL.GL_RENDERBUFFER, rb)
    GL.glRenderbufferStorage(GL.GL_RENDERBUFFER, GL.GL_RGBA8, W, H)
    GL.glBindFramebuffer(GL.GL_FRAMEBUFFER, fbo)
    GL.glFramebufferRenderbuffer(GL.GL_FRAMEBUFFER, GL.GL_COLOR_ATTACHMENT0, GL.GL_RENDERBUFFER, rb)
    GL.glViewport(0, 0, W, H)
    GL.glMatrixMode(GL.GL_PROJECTION)
    GL.glLoadIdentity()
    GL.glOrtho(0, W, 0, H, -100, 100)
    GL.glMatrixMode(GL.GL_MODELVIEW)
    GL.glLoadIdentity()
    GL.glDisable(GL.GL_CULL_FACE)
    covered = {}
    for i, tri in enumerate(TRIANGLES):
        GL.glClearColor(0, 0, 0, 0)
        GL.glClear(GL.GL_COLOR_BUFFER_BIT)
        GL.glColor4f(1, 1, 1, 1)
        GL.glBegin(GL.GL_TRIANGLES)
        for x, y in tri:
            GL.glVertex3f(x, y, -10.0)
        GL.glEnd()
        px = np.frombuffer(GL.glReadPixels(0, 0, W, H, GL.GL_RED, GL.GL_UNSIGNED_BYTE), np.uint8).reshape(H, W)
        ys, xs = np.nonzero(px)
        covered[i + 1] = {(int(x), H - 1 - int(y)) for x, y in zip(xs, ys)}
    return covered


def test_samples_on_edges_belong_where_mesa_puts_them(tmp_path):
    mesa = drawn_by_mesa()
    ours = converted(tmp_path)
    # The square's halves share their diagonal and tile it exactly.
    assert len(mesa[1] | mesa[2]) == 16 * 16 and not mesa[1] & mesa[2]
    # Mesa's rule as measured: rows 4..19 from the bottom, columns 4..19.
    assert {y for _, y in mesa[1] | mesa[2]} == set(range(H - 20, H - 4))
    assert {x for x, _ in mesa[1] | mesa[2]} == set(range(4, 20))
    for obj in mesa:
        assert ours.get(obj, set()) == mesa[obj], f"triangle {obj}: " \
            f"{len(ours.get(obj, set()) - mesa[obj])} pixels Mesa does not cover, " \
            f"{len(mesa[obj] - ours.get(obj, set()))} it covers missing"

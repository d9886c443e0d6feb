"""The reduced capture's format (rbcd.gl2rbt.reduced; docs/gl-capture.md):
written and read back without apitrace."""
import lzma
import os

import pytest

from rbcd.gl2rbt.apitrace import PointerType
from rbcd.gl2rbt.errors import ConvertError
from rbcd.gl2rbt.glstate.framebuffers import texture_image_digest
from rbcd.gl2rbt.reduced import REDUCED_HEADER, ReducedWriter, is_reduced_capture, read_reduced_calls

CALLS = [
    (1, "glViewport", [("x", 0), ("y", 0), ("width", 128), ("height", 96)], None, 1),
    (2, "glTexEnvi", [("target", "GL_TEXTURE_ENV"), ("pname", "GL_TEXTURE_ENV_MODE"), ("param", "GL_MODULATE")],
     None, 0),   # cannot move a fragment: left out
    (3, "glTexImage2D", [("target", "GL_TEXTURE_2D"), ("level", 0), ("internalformat", "GL_RGBA8"), ("width", 64),
                         ("height", 32), ("border", 0), ("format", "GL_RGBA"), ("type", "GL_UNSIGNED_BYTE"),
                         ("pixels", b"\xff" * 8192)], None, 0),   # its size kept
    (4, "glBindTexture", [("target", "GL_TEXTURE_2D"), ("texture", 7)], None, 0),   # kept: rules name textures
    (5, "glVertexPointer", [("size", 3), ("type", "GL_FLOAT"), ("stride", 0), ("pointer", PointerType(0x7F00))], None,
     0),
    (6, "glXSwapBuffers", [("dpy", PointerType(1)), ("drawable", 2)], None, 32),
    (7, "glTexEnvf", [("target", "GL_TEXTURE_FILTER_CONTROL"), ("pname", "GL_TEXTURE_LOD_BIAS"), ("param", 1.0)],
     None, 0),   # kept: a texture unit's bias moves a vertex shader's texture() level
]


def write(path, calls=CALLS):
    w = ReducedWriter(str(path))
    for c in calls:
        w.call(c)
    w.commit()


def test_round_trip_keeps_what_the_emulation_reads(tmp_path):
    p = tmp_path / "c.calls.xz"
    write(p)
    assert is_reduced_capture(str(p))
    got = list(read_reduced_calls(str(p)))
    assert [c[0] for c in got] == [1, 3, 4, 5, 6, 7], \
        "a texture environment call is left out, the binding and a texture unit's bias kept"
    assert got[1][2] == CALLS[2][2][:-1] + [("pixels", ("rbcd-digest", texture_image_digest(dict(CALLS[2][2]))))], \
        "a texture's size kept, and its image's digest in place of its pixels"
    assert got[3][2] == [("size", 3), ("type", "GL_FLOAT"), ("stride", 0), ("pointer", 0x7F00)] \
        and type(got[3][2][3][1]) is int, \
        "pointers become plain integers"
    assert got[0] == CALLS[0] and got[4][4] == 32, "arguments and call flags as read"
    assert not [f for f in os.listdir(tmp_path) if f.startswith(".")], "no temporary left"


def test_damaged_files_are_refused_naming_where(tmp_path):
    p = tmp_path / "c.calls.xz"
    write(p)
    data = p.read_bytes()
    bad = tmp_path / "bad.calls.xz"

    def refused(body, words):
        bad.write_bytes(body)
        with pytest.raises(ConvertError, match=words):
            list(read_reduced_calls(str(bad)))

    refused(data[:len(data) // 2], "does not decode|cut short")
    refused(lzma.compress(b"not a pickle"), "before its first call: the reduced capture does not decode")
    # A header and calls but no end record: a file cut between records.
    w = ReducedWriter(str(bad))
    w.call(CALLS[0])
    w.out.write(w.z.flush())
    w.out.commit()
    with pytest.raises(ConvertError, match=r"after call 1: the reduced capture is cut short"):
        list(read_reduced_calls(str(bad)))
    # Calls out of order.
    write(bad, [CALLS[4], CALLS[0]])
    with pytest.raises(ConvertError, match=r"after call 5: .*unexpected record"):
        list(read_reduced_calls(str(bad)))
    # An argument named twice (apitrace names each once; the emulation
    # reads some by position and some by name).
    write(bad, [CALLS[0], (2, "glDepthFunc", [("func", "GL_LESS"), ("func", "GL_ALWAYS")], None, 0)])
    with pytest.raises(ConvertError, match=r"after call 1: .*unexpected record"):
        list(read_reduced_calls(str(bad)))


def test_an_xz_file_of_something_else(tmp_path):
    p = tmp_path / "other.xz"
    p.write_bytes(lzma.compress(b""))
    with pytest.raises(ConvertError, match="not a reduced capture"):
        list(read_reduced_calls(str(p)))
    assert not is_reduced_capture(str(tmp_path / "missing.xz"))


def test_pixel_rectangles_keep_their_size_not_their_pixels(tmp_path):
    """glDrawPixels and glBitmap, read for their size and what they would
    write (not emulated with depth writes on): kept, their pixels left out."""
    p = tmp_path / "c.calls.xz"
    write(p, CALLS[:1] + [
        (2, "glDrawPixels", [("width", 10), ("height", 10), ("format", "GL_RGBA"), ("type", "GL_UNSIGNED_BYTE"),
                             ("pixels", b"\0" * 400)], None, 0),
        (3, "glBitmap", [("width", 0), ("height", 0), ("xorig", 0.0), ("yorig", 0.0), ("xmove", 5.0), ("ymove", 0.0),
                         ("bitmap", None)], None, 0),
        (4, "glPrimitiveRestartNV", [], None, 0)] + CALLS[5:6])
    got = list(read_reduced_calls(str(p)))
    assert [c[1] for c in got] == ["glViewport", "glDrawPixels", "glBitmap", "glPrimitiveRestartNV", "glXSwapBuffers"]
    assert got[1][2] == [("width", 10), ("height", 10), ("format", "GL_RGBA"), ("type", "GL_UNSIGNED_BYTE"),
                         ("pixels", None)]


def test_the_source_s_size_is_carried_and_credited_within_bounds(tmp_path):
    """A reduced capture names the size of the capture it was reduced from
    (version 4 on), and the converter's bounds take that size, up to 16
    times the reduced capture's own, and at least its own: a reduced
    capture of a large capture is no longer held to the smaller bounds of
    its own size (a 72.5 KB reduction of a 597 KB capture was refused
    where the capture was taken; R21-8), and a reduced capture cannot
    buy bounds far past its own size by its header's word (a claim 1000
    times an 11 KB file's had bought 80 minutes; R22-6)."""
    from rbcd.gl2rbt.reduced import REDUCED_SOURCE_CREDIT, reduced_header, source_bytes
    for claimed, credit in ((0, "own"), (5_000, "claimed"), (1 << 62, "capped")):
        p = tmp_path / f"{credit}.xz"
        w = ReducedWriter(str(p), claimed)
        for c in CALLS:
            w.call(c)
        w.commit()
        own = p.stat().st_size
        assert reduced_header(str(p)) == ("rbcd-reduced-capture", REDUCED_HEADER[1], claimed)
        want = {"own": own, "claimed": claimed, "capped": REDUCED_SOURCE_CREDIT * own}[credit]
        assert source_bytes(str(p)) == want, (credit, own)
    plain = tmp_path / "capture.trace"
    plain.write_bytes(bytes(12345))
    assert source_bytes(str(plain)) == 12345 and source_bytes(str(tmp_path / "none")) == 0

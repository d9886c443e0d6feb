"""The OpenGL registry as the converter reads it (rbcd.gl2rbt.gl_registry;
docs/gl-capture.md): enumerants by value named in their parameter's group,
apitrace's parameter names, and the cache, which is rebuilt whatever it
holds and never waited on."""
import hashlib
import json
import os

import pytest

from rbcd.gl2rbt import gl_registry
from rbcd.gl2rbt.gl_registry import named_enumerants, registry
from rbcd.gl2rbt import window_registry as window_registry_module
from rbcd.gl2rbt.errors import ToolError
from rbcd.gl2rbt.gl_tables import SWAP_HANDLES
from rbcd.gl2rbt.window_registry import window_registry

pytestmark = pytest.mark.skipif(not os.path.exists(gl_registry.REGISTRY),
                                reason="khronos-api is missing (scripts/setup.sh --gl installs it)")


@pytest.mark.parametrize("fn, args, want", [
    ("glCullFace", [("mode", 0x0404)], [("mode", "GL_FRONT")]),
    ("glDrawArrays", [("mode", 0), ("first", 0), ("count", 3)], [("mode", "GL_POINTS"), ("first", 0), ("count", 3)]),
    ("glDrawArrays", [("mode", 4), ("first", 4), ("count", 4)], [("mode", "GL_TRIANGLES"), ("first", 4), ("count", 4)]),
    ("glDrawBuffer", [("mode", 0)], [("mode", "GL_NONE")]),
    ("glBlendFunc", [("sfactor", 0), ("dfactor", 1)], [("sfactor", "GL_ZERO"), ("dfactor", "GL_ONE")]),
    ("glEnable", [("cap", 0x0B71)], [("cap", "GL_DEPTH_TEST")]),
    ("glEnable", [("cap", 0x7FFF1234)], [("cap", 0x7FFF1234)]),
    ("glBindTexture", [("target", 0x8D65), ("texture", 0x0404)], [("target", "GL_TEXTURE_EXTERNAL_OES"),
                                                                  ("texture", 0x0404)]),
    ("glClipControl", [("origin", 0x8CA2), ("depth", 0x935E)], [("origin", "GL_UPPER_LEFT"),
                                                              ("depth", "GL_NEGATIVE_ONE_TO_ONE")]),
    # By name in any order; by position only when no argument has one of
    # the function's names.
    ("glDrawArrays", [("count", 4), ("mode", 4), ("first", 0)], [("count", 4), ("mode", "GL_TRIANGLES"), ("first", 0)]),
    ("glDrawArrays", [("a0", 4), ("a1", 0), ("a2", 4)], [("a0", "GL_TRIANGLES"), ("a1", 0), ("a2", 4)]),
    ("glXSwapBuffers", [("dpy", 1), ("drawable", 2)], [("dpy", 1), ("drawable", 2)]),
    ("glDepthFunc", [("func", 1 << 40)], [("func", 1 << 40)]),
    ("glDepthFunc", [("func", True)], [("func", True)]),
    # gl.xml puts the _EXT alias, not the core name, in the group: the core
    # name all the same, as apitrace writes it.
    ("glEnable", [("cap", 0x806F)], [("cap", "GL_TEXTURE_3D")]),
    ("glEnable", [("cap", 0x803A)], [("cap", "GL_RESCALE_NORMAL")]),
    # No core name: _EXT before ANGLE's alias, as apitrace writes it.
    ("glCompressedTexImage2D", [("target", 0x0DE1), ("level", 0), ("internalformat", 0x83F2), ("width", 4),
                                ("height", 4), ("border", 0), ("imageSize", 16), ("data", b"")],
     [("target", "GL_TEXTURE_2D"), ("level", 0), ("internalformat", "GL_COMPRESSED_RGBA_S3TC_DXT3_EXT"),
      ("width", 4), ("height", 4), ("border", 0), ("imageSize", 16), ("data", b"")]),
    # A GLint the registry groups (apitrace writes it by name), within its
    # group alone: 3 there is a component count.
    ("glTexImage2D", [("internalformat", 0x81A6)], [("internalformat", "GL_DEPTH_COMPONENT24")]),
    ("glTexImage2D", [("internalformat", 3)], [("internalformat", 3)]),
    ("glDrawBuffers", [("n", 2), ("bufs", [0x8CE0, 0])], [("n", 2), ("bufs", ["GL_COLOR_ATTACHMENT0", "GL_NONE"])]),
], ids=["front", "points", "triangles_not_a_count", "draw_buffer_none", "blend_zero_one", "cap", "no_such_value",
        "suffixed_only_name", "clip_control", "by_name", "by_position", "window_system", "past_32_bits", "boolean",
        "core_name_of_an_ext_group_member", "rescale_normal", "ext_before_angle", "grouped_glint",
        "component_count", "list"])
def test_an_enumerant_by_value_is_named_in_its_parameter_s_group(fn, args, want):
    assert named_enumerants(fn, args) == want


def test_apitrace_s_names_where_they_differ_from_the_registry_s():
    assert [p[0] for p in registry().signature("glDepthRange")] == ["zNear", "zFar"]
    assert [p[0] for p in registry().signature("glOrthof")] == ["left", "right", "bottom", "top", "zNear", "zFar"]
    # The registry of 2022 lists this EXT form with nine parameters.
    assert [p[0] for p in registry().signature("glDrawArraysInstancedBaseInstanceEXT")] == [
        "mode", "first", "count", "instancecount", "baseinstance"]
    # apitrace's names of the EXT_draw_instanced forms, not the registry's
    # start and primcount (the converter's own reduced captures had been refused).
    assert [p[0] for p in registry().signature("glDrawArraysInstancedEXT")] == ["mode", "first", "count",
                                                                               "instancecount"]
    assert [p[0] for p in registry().signature("glDrawElementsInstancedEXT")] == ["mode", "count", "type", "indices",
                                                                                 "instancecount"]
    assert [p[3] for p in registry().signature("glLoadMatrixf")] == [16]
    assert registry().signature("glXSwapBuffers") is None


def sealed(body):
    """A cache file's content as _load writes it: the SHA-256 digest of the
    JSON on a line before it."""
    return hashlib.sha256(body).hexdigest().encode() + b"\n" + body


@pytest.mark.parametrize("content", [None, b"", b"{", sealed(b"{"), sealed(b"[1]"), sealed(b'{"format": 4}'),
                                     sealed(b'{"format": 4, "commands": {"glCullFace": [[1, 2, 3, 4]]}, '
                                            b'"groups": {}}'),
                                     sealed(b'{"format": 4, "commands": {}, "groups": {"CullFaceMode": [["x", 1]]}}'),
                                     sealed(b'{"format": 4, "commands": {"glCullFace": [[null, "GLenum", null, '
                                            b'null]]}, "groups": {}}'),
                                     sealed(b'{"format": 4, "commands": {}, "groups": {}}'),
                                     "empty_sentinel", "renamed", "deleted", "digest_only", "unsealed",
                                     sealed(b"[" * 100000), "fifo", "directory"],
                         ids=["absent", "empty", "cut", "sealed_cut", "list", "no_tables", "bad_command", "bad_group",
                              "null_parameter_name", "cut_down", "empty_sentinel", "renamed", "deleted",
                              "digest_only", "unsealed", "deep", "fifo", "directory"])
def test_a_cache_is_rebuilt_whatever_it_holds(tmp_path, monkeypatch, content):
    """The registry read again and the answer the same whatever the cache
    file holds (never a traceback, never waiting on a FIFO), and a cache of
    the registry written where one can be. A cache edited by hand, however
    well shaped (glCullFace's parameter renamed, or glCullFace deleted:
    round 36's D5, the capture had been blamed with exit 2), is not the
    digest's and is rebuilt."""
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    monkeypatch.setattr(gl_registry, "_REGISTRY", None)
    cache = gl_registry._cache_path(os.stat(gl_registry.REGISTRY))
    os.makedirs(os.path.dirname(cache))
    if content in ("empty_sentinel", "renamed", "deleted", "digest_only", "unsealed"):
        data = gl_registry._parse(gl_registry.REGISTRY)
        if content == "empty_sentinel":
            # The whole registry's cache but glDrawArrays' parameters (round
            # 36's D4: an IndexError, the capture blamed); sealed as _load
            # seals it, so the shape checks are what refuse it.
            data["commands"]["glDrawArrays"] = []
            content = sealed(json.dumps(data).encode())
        elif content == "unsealed":   # the right content, no digest
            content = json.dumps(data, separators=(",", ":")).encode()
        elif content == "digest_only":
            content = sealed(json.dumps(data, separators=(",", ":")).encode()).split(b"\n")[0] + b"\n"
        else:
            good = sealed(json.dumps(data, separators=(",", ":")).encode())
            if content == "renamed":
                data["commands"]["glCullFace"][0][0] = "face"
            else:
                del data["commands"]["glCullFace"]
            # (the digest of the cache as written, the content edited)
            content = good.split(b"\n")[0] + b"\n" + json.dumps(data, separators=(",", ":")).encode()
    if content == "fifo":
        os.mkfifo(cache)
    elif content == "directory":
        os.mkdir(cache)
    elif content is not None:
        with open(cache, "wb") as f:
            f.write(content)
    assert registry().signature("glCullFace")[0][0] == "mode"
    assert named_enumerants("glCullFace", [("mode", 0x0404)]) == [("mode", "GL_FRONT")]
    if content != "directory":
        with open(cache, "rb") as f:
            digest, _, body = f.read().partition(b"\n")
        assert digest == hashlib.sha256(body).hexdigest().encode()
        assert json.loads(body)["format"] == gl_registry.CACHE_FORMAT
    monkeypatch.setattr(gl_registry, "_REGISTRY", None)
    assert named_enumerants("glCullFace", [("mode", 0x0405)]) == [("mode", "GL_BACK")]
    # The cache written is read back as it is (not rebuilt each run).
    if content != "directory":
        monkeypatch.setattr(gl_registry, "_parse", None)
        monkeypatch.setattr(gl_registry, "_REGISTRY", None)
        assert registry().signature("glCullFace")[0][0] == "mode"


def test_a_relative_cache_home_is_ignored(tmp_path, monkeypatch):
    """XDG's rule: a relative XDG_CACHE_HOME is ignored (the cache would
    follow the working folder); a relative HOME too, and then there is no
    cache (round 35's D7: one left in the working folder)."""
    monkeypatch.setenv("XDG_CACHE_HOME", "rel")
    monkeypatch.setenv("HOME", str(tmp_path))
    st = os.stat(gl_registry.REGISTRY)
    assert gl_registry._cache_path(st).startswith(str(tmp_path / ".cache" / "rbcd") + "/")
    monkeypatch.setenv("HOME", "relhome")
    assert gl_registry._cache_path(st) is None
    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(gl_registry, "_REGISTRY", None)
    assert named_enumerants("glCullFace", [("mode", 0x0404)]) == [("mode", "GL_FRONT")]
    assert not os.path.exists(tmp_path / "relhome")


def test_window_system_functions_as_apitrace_records_them():
    """The window systems' functions by apitrace's parameter names: GLX's
    and WGL's registries with apitrace's names where they differ, EGL's
    headers, apitrace's own (GDI's pixel-format calls under wgl names);
    None for a name none has. Every buffer swap's handle (SWAP_HANDLES) is
    one of its function's parameters."""
    ws = window_registry()
    assert ws.signature("glXMakeCurrent") == ("dpy", "drawable", "ctx")
    assert ws.signature("glXMakeContextCurrent") == ("dpy", "draw", "read", "ctx")
    assert ws.signature("eglMakeCurrent") == ("dpy", "draw", "read", "ctx")
    assert ws.signature("eglCreateContext") == ("dpy", "config", "share_context", "attrib_list")
    assert ws.signature("eglSwapBuffersWithDamageKHR") == ("dpy", "surface", "rects", "n_rects")
    assert ws.signature("wglMakeCurrent") == ("hdc", "hglrc")   # (the registry's hDc, newContext)
    assert ws.signature("glXCreateNewContext") == ("dpy", "config", "renderType", "shareList", "direct")
    assert ws.signature("glXCreateContextAttribsARB") == ("dpy", "config", "share_context", "direct",
                                                          "attrib_list")
    assert ws.signature("wglSwapBuffers") == ("hdc",)
    assert ws.signature("eglGetSyncValuesCHROMIUM") == ("dpy", "surface", "ust", "msc", "sbc")
    for name in ("glXFrobnicateMESA", "eglFrobnicateKHR", "wglFrobnicate", "glXMakeCurrentARB"):
        assert ws.signature(name) is None, name
    for fn, handle in SWAP_HANDLES.items():
        assert handle in ws.signature(fn), fn
    assert registry().signature("glGenQueriesANGLE") == (("n", None, None, None), ("ids", None, None, None))


def test_window_system_enumerants_by_value():
    """An enumerant of GLX or EGL by name is its registry's value; a number
    is itself; apitrace's tuple of flags (with the bits it has no name for)
    their bits together; an attribute list up to its end attribute, the
    last of an attribute given twice; anything else refused by
    attributes()."""
    ws = window_registry()
    assert ws.value("GLX_CONTEXT_MAJOR_VERSION_ARB") == 0x2091
    assert ws.value("GLX_CONTEXT_PROFILE_MASK_ARB") == 0x9126
    assert ws.value("EGL_OPENGL_API") == 0x30A2
    assert ws.value("EGL_CONTEXT_MAJOR_VERSION") == ws.value("EGL_CONTEXT_CLIENT_VERSION") == 0x3098
    assert ws.value("EGL_NONE") == 0x3038
    assert ws.value(("GLX_CONTEXT_CORE_PROFILE_BIT_ARB", "GLX_CONTEXT_COMPATIBILITY_PROFILE_BIT_ARB")) == 3
    assert ws.value(("GLX_CONTEXT_CORE_PROFILE_BIT_ARB", 8)) == 9
    assert ws.value(()) == 0
    for x in ("GLX_NO_SUCH", True, 1.0, None, [1], ("GLX_NO_SUCH",), (1, 2), ("GLX_CONTEXT_CORE_PROFILE_BIT_ARB", 1.0)):
        assert ws.value(x) is None, x
    assert ws.attributes(["GLX_CONTEXT_MAJOR_VERSION_ARB", 3, 0x2092, 2, "GLX_CONTEXT_MAJOR_VERSION_ARB", 4, 0,
                          0x9126, 2], 0) == {0x2091: 4, 0x2092: 2}
    assert ws.attributes([0x3098, 3, "EGL_NONE", 0x30FD, 2], "EGL_NONE") == {0x3098: 3}
    assert ws.attributes(None, 0) == {}
    # A Bool attribute's value as apitrace writes it (SuperTuxKart's
    # GLX_CONTEXT_OPENGL_NO_ERROR_ARB).
    assert ws.attributes(["GLX_CONTEXT_OPENGL_NO_ERROR_ARB", "False", 0x2091, 3], 0) == {0x31B3: 0, 0x2091: 3}
    assert ws.attributes(["GLX_CONTEXT_OPENGL_NO_ERROR_ARB", True], 0) == {0x31B3: 1}
    for bad in ([[1], 3], [0x2091, 3.0], [0x2091, 1.0], ["GLX_NO_SUCH", 1], 7, "GLX_NONE", (0x2091, 3), [True, 1],
                ["False", 1], [0x2091, "Maybe"], [0x9126, "True"], [0x9126, True]):
        with pytest.raises(ValueError):
            ws.attributes(bad, 0)


def test_a_missing_window_system_registry_is_one_line(monkeypatch):
    """Without EGL's header (libegl-dev) or GLX's registry (khronos-api),
    the call that needs one fails with a message naming the file and the
    package, not a traceback."""
    monkeypatch.setattr(window_registry_module, "_REGISTRY", None)
    monkeypatch.setattr(window_registry_module, "EGL_HEADERS", ("/nonexistent/EGL/egl.h",))
    ws = window_registry()
    assert ws.signature("glXMakeCurrent") == ("dpy", "drawable", "ctx")
    with pytest.raises(ToolError, match=r"EGL's header /nonexistent/EGL/egl.h is missing .*libegl-dev"):
        ws.signature("eglMakeCurrent")
    monkeypatch.setattr(window_registry_module, "_REGISTRY", None)
    monkeypatch.setattr(window_registry_module, "XML_REGISTRIES", ("/nonexistent/glx.xml",))
    with pytest.raises(ToolError, match=r"registry /nonexistent/glx.xml is missing .*khronos-api"):
        window_registry()


def test_a_cache_is_this_code_s_own(tmp_path, monkeypatch):
    """The cache file is named by this module's own digest (another build
    of the converter may read the registry otherwise under the same
    CACHE_FORMAT: round 38's D12); writing one removes the caches of
    other keys, never another file."""
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    monkeypatch.setattr(gl_registry, "_REGISTRY", None)
    cache = gl_registry._cache_path(os.stat(gl_registry.REGISTRY))
    with open(gl_registry.__file__, "rb") as f:
        assert hashlib.sha256(f.read()).hexdigest()[:16] in os.path.basename(cache)
    os.makedirs(os.path.dirname(cache))
    stale = tmp_path / "rbcd" / "gl-registry-4-0123456789abcdef-1-2.json"
    other = tmp_path / "rbcd" / "notes.json"
    stale.write_bytes(b"x")
    other.write_bytes(b"y")
    assert registry().signature("glCullFace")[0][0] == "mode"
    assert os.path.exists(cache) and not stale.exists() and other.read_bytes() == b"y"

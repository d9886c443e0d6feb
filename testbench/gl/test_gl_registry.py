"""The OpenGL registry as the converter reads it (rbcd.gl2rbt.gl_registry;
docs/gl-capture.md): enumerants by value named in their parameter's group,
apitrace's parameter names, and the cache, which is rebuilt whatever it
holds and never waited on."""
import json
import os

import pytest

from rbcd.gl2rbt import gl_registry
from rbcd.gl2rbt.gl_registry import named_enumerants, registry

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


@pytest.mark.parametrize("content", [None, b"", b"{", b"[1]", b'{"format": 3}',
                                     b'{"format": 3, "commands": {"glCullFace": [[1, 2, 3, 4]]}, "groups": {}}',
                                     b'{"format": 3, "commands": {}, "groups": {"CullFaceMode": [["x", 1]]}}',
                                     b'{"format": 3, "commands": {"glCullFace": [[null, "GLenum", null, null]]}, '
                                     b'"groups": {}}',
                                     b'{"format": 3, "commands": {}, "groups": {}}',
                                     "empty_sentinel",
                                     b"[" * 100000, "fifo", "directory"],
                         ids=["absent", "empty", "cut", "list", "no_tables", "bad_command", "bad_group",
                              "null_parameter_name", "cut_down", "empty_sentinel", "deep", "fifo", "directory"])
def test_a_cache_is_rebuilt_whatever_it_holds(tmp_path, monkeypatch, content):
    """The registry read again and the answer the same whatever the cache
    file holds (never a traceback, never waiting on a FIFO), and a cache of
    the registry written where one can be."""
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    monkeypatch.setattr(gl_registry, "_REGISTRY", None)
    cache = gl_registry._cache_path(os.stat(gl_registry.REGISTRY))
    os.makedirs(os.path.dirname(cache))
    if content == "empty_sentinel":
        # The whole registry's cache but glDrawArrays' parameters (round
        # 36's D4: an IndexError, the capture blamed).
        data = gl_registry._parse(gl_registry.REGISTRY)
        data["commands"]["glDrawArrays"] = []
        content = json.dumps(data).encode()
    if content == "fifo":
        os.mkfifo(cache)
    elif content == "directory":
        os.mkdir(cache)
    elif content is not None:
        with open(cache, "wb") as f:
            f.write(content)
    assert named_enumerants("glCullFace", [("mode", 0x0404)]) == [("mode", "GL_FRONT")]
    if content != "directory":
        with open(cache) as f:
            assert json.load(f)["format"] == gl_registry.CACHE_FORMAT
    monkeypatch.setattr(gl_registry, "_REGISTRY", None)
    assert named_enumerants("glCullFace", [("mode", 0x0405)]) == [("mode", "GL_BACK")]


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

"""Property tests of rbcd-gl2rbt's readers with hypothesis (Debian
python3-hypothesis): the call handlers, the reduced-capture reader and the
selection-file reader fed generated input (NaN, infinities, huge and negative
numbers, wrong types, missing arguments, truncated and flipped files) raise
only the converter's own error, ConvertError (one line, exit 2), never
anything else. Derandomized (a fixed seed) with a bounded number of
examples, so CI runs the same cases in a few seconds; HYPOTHESIS_EXAMPLES
raises the count for a longer hunt by hand."""
import argparse
import io
import lzma
import os
import pickle

import pytest

pytest.importorskip("numpy", reason="python3-numpy is missing (scripts/setup.sh --gl installs it)")
hypothesis = pytest.importorskip("hypothesis", reason="python3-hypothesis is missing (scripts/setup.sh installs it)")
from hypothesis import HealthCheck, given, settings, strategies as st  # noqa: E402

from rbcd.gl2rbt.converter import Converter  # noqa: E402
from rbcd.gl2rbt.errors import ConvertError  # noqa: E402
from rbcd.gl2rbt.reduced import REDUCED_END, REDUCED_HEADER, read_reduced_calls  # noqa: E402
from rbcd.gl2rbt.selection import Selection  # noqa: E402

EXAMPLES = int(os.environ.get("HYPOTHESIS_EXAMPLES", "300"))
FIXED = settings(max_examples=EXAMPLES, deadline=None, derandomize=True, database=None,
                 suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much])

# Values a capture could hold where a handler expects something else.
ENUMS = ["GL_TRIANGLES", "GL_TRIANGLE_STRIP", "GL_POINTS", "GL_FLOAT", "GL_UNSIGNED_SHORT", "GL_ARRAY_BUFFER",
         "GL_ELEMENT_ARRAY_BUFFER", "GL_UNIFORM_BUFFER", "GL_TEXTURE_2D", "GL_TEXTURE_BUFFER", "GL_MODELVIEW",
         "GL_PROJECTION", "GL_DEPTH_TEST", "GL_CULL_FACE", "GL_BACK", "GL_FRONT", "GL_CCW", "GL_LESS",
         "GL_DEPTH_BUFFER_BIT", "GL_FRAMEBUFFER", "GL_DEPTH_ATTACHMENT", "GL_VERTEX_SHADER", "GL_TRUE",
         "GL_DEBUG_SOURCE_APPLICATION", "GL_TEXTURE3", "GL_CLIP_PLANE0", "GL_BOGUS", ""]
NUMBERS = st.one_of(st.integers(-2 ** 70, 2 ** 70), st.floats(allow_nan=True, allow_infinity=True),
                    st.sampled_from([0, 1, 3, -1, 2 ** 31, 2 ** 32, 2 ** 63, 2 ** 64]))
SCALARS = st.one_of(st.none(), st.booleans(), NUMBERS, st.sampled_from(ENUMS), st.text(max_size=20),
                    st.binary(max_size=64))
VALUES = st.one_of(SCALARS, st.lists(SCALARS, max_size=20), st.tuples(st.sampled_from(ENUMS)))
ARG_NAMES = ["target", "buffer", "buffers", "size", "data", "offset", "length", "mode", "count", "first", "type",
             "indices", "index", "array", "arrays", "program", "shader", "string", "name", "location", "value",
             "transpose", "x", "y", "z", "width", "height", "pointer", "stride", "normalized", "divisor",
             "instancecount", "basevertex", "start", "end", "id", "message", "source", "marker", "texture",
             "framebuffer", "attachment", "renderbuffer", "internalformat", "level", "dest", "src", "n", "cap",
             "drawcount", "uniformBlockIndex", "uniformBlockBinding", "readTarget", "writeTarget",
             "readOffset", "writeOffset", "access", "mask", "depth", "angle", "left", "right", "bottom", "top"]
# No program can be linked: draws stay on the fixed-function path, which
# needs no Mesa (the shader path's own tests run Mesa on real captures).
HANDLED = sorted(n for n in Converter.HANDLERS if n != "glLinkProgram")


def converter():
    args = argparse.Namespace(screen=(64, 48), tile=[16, 16], depth_bits=24, select=None, frame_range=(0, None))
    return Converter(args, io.BytesIO(), None)


call = st.tuples(st.sampled_from(HANDLED + ["glVertex3f", "glBegin", "glEnd", "glSomethingNew", "memcpy"]),
                 st.lists(st.tuples(st.sampled_from(ARG_NAMES), VALUES), max_size=8),
                 st.one_of(st.none(), NUMBERS), st.sampled_from([0, 1, 32]))


@FIXED
@given(st.lists(call, min_size=1, max_size=12))
def test_handlers_raise_only_the_converters_error(calls):
    conv = converter()
    for no, (name, args, ret, flags) in enumerate(calls, 1):
        try:
            conv.handle((no, name, args, ret, flags))
        except ConvertError:
            return


def reduced_file(tmp, records, cut=None, flip=None):
    raw = io.BytesIO()
    for r in records:
        pickle.dump(r, raw, protocol=4)
    data = lzma.compress(raw.getvalue())
    if cut is not None:
        data = data[:cut % (len(data) + 1)]
    if flip is not None and data:
        i = flip % len(data)
        data = data[:i] + bytes([data[i] ^ 0x55]) + data[i + 1:]
    path = os.path.join(tmp, "r.xz")
    with open(path, "wb") as f:
        f.write(data)
    return path


record = st.one_of(
    st.tuples(st.one_of(st.integers(-5, 2 ** 64), NUMBERS), st.sampled_from(HANDLED[:20] + ["glXSwapBuffers"]),
              st.lists(st.tuples(st.sampled_from(ARG_NAMES), VALUES), max_size=4), SCALARS,
              st.one_of(st.integers(0, 64), NUMBERS)),
    st.tuples(st.just(REDUCED_END), st.integers(-1, 5)),
    VALUES)


@FIXED
@given(st.lists(record, max_size=8), st.booleans(), st.one_of(st.none(), st.integers(0, 10 ** 6)),
       st.one_of(st.none(), st.integers(0, 10 ** 6)))
def test_reduced_reader_raises_only_the_converters_error(tmp_path_factory, records, header, cut, flip):
    tmp = tmp_path_factory.mktemp("reduced")
    path = reduced_file(tmp, ([REDUCED_HEADER] if header else []) + records, cut, flip)
    conv = converter()
    try:
        for c in read_reduced_calls(path):
            conv.handle(c)
    except ConvertError:
        pass


toml_value = st.one_of(st.integers(-2 ** 70, 2 ** 70).map(str), st.sampled_from(
    ["nan", "inf", "-inf", "1e400", "true", "'a'", '"x"', "[]", "[1, 2]", "[2, 1]", "[1, 'a']", "{}",
     '["0123abcd"]', '["Solid Pass"]', "[[1]]", "-1", "4294967296", "1.5", '"perspective"', '"modelview"']))
toml_key = st.sampled_from(sorted(Selection.KEYS) + ["first_entity_id", "max_entity_id", "track_radius",
                                                      "up_axis", "bogus"])
toml_table = st.sampled_from(["[[object]]", "[[exclude]]", "[settings]", "[object]", "[[settings]]", "[x]", ""])
toml_doc = st.lists(st.tuples(toml_table, st.lists(st.tuples(toml_key, toml_value), max_size=5)), max_size=4) \
    .map(lambda t: "\n".join(head + "\n" + "\n".join(f"{k} = {v}" for k, v in body) for head, body in t))


@FIXED
@given(st.one_of(toml_doc, st.text(max_size=200)))
def test_selection_reader_raises_only_the_converters_error(tmp_path_factory, text):
    path = tmp_path_factory.mktemp("sel") / "r.toml"
    path.write_bytes(text.encode("utf-8", "surrogatepass"))
    try:
        s = Selection(str(path))
    except ConvertError:
        return
    d = {"call": 1, "frame": 0, "vertices": 3, "texture": 0, "depth_write": True, "projection": "perspective",
         "own_modelview": False, "screen_area": 10.0, "program": "", "pass": "", "instances": 1}
    s.classify(d)

"""Selection files and the entity tracker of rbcd.gl2rbt (docs/gl-capture.md,
"Identified off line"), without Xvfb or apitrace."""
import os
import re
import subprocess
import sys

import pytest

np = pytest.importorskip("numpy", reason="python3-numpy is missing (scripts/setup.sh --gl installs it)")
from rbcd.gl2rbt.entities import EntityTracker  # noqa: E402
from rbcd.gl2rbt.errors import ConvertError  # noqa: E402
from rbcd.gl2rbt.selection import Selection  # noqa: E402


def rules(tmp_path, text):
    p = tmp_path / "rules.toml"
    p.write_text(text)
    return Selection(str(p))


def draw(**kw):
    d = {"call": 10, "frame": 0, "vertices": 36, "texture": 0, "depth_write": True, "projection": "perspective",
         "own_modelview": True, "screen_area": 500.0, "program": "", "pass": "", "instances": 1,
         "texture_image": "", "draw_index": 0}
    d.update(kw)
    return d


def test_exclusions_first_then_the_first_matching_object(tmp_path):
    s = rules(tmp_path, """
[[object]]
name = "crate"
id = 3
vertex_count = [24, 36]
texture = [7, 8]
[[object]]
name = "anything textured 9"
id = 4
texture = [9]
[[object]]
name = "players"
group_by = "modelview"
calls = [100, 200]
[[exclude]]
name = "hud"
projection = "orthographic"
""")
    assert s.classify(draw(texture=7)) == (3, "crate")
    assert s.classify(draw(texture=7, projection="orthographic")) == (None, "hud"), "[[exclude]] comes first"
    assert s.classify(draw(texture=7, vertices=37)) == (None, "no rule")
    assert s.classify(draw(texture=9, vertices=37)) == (4, "anything textured 9")
    assert s.classify(draw(call=150)) == ("entity", "players")
    assert s.classify(draw(call=201)) == (None, "no rule")


@pytest.mark.parametrize("field, value, inside, outside", [
    ("frames", [2, 4], {"frame": 4}, {"frame": 5}),
    ("depth_write", False, {"depth_write": False}, {}),
    ("modelview_differs_from_view", False, {"own_modelview": False}, {}),
    ("min_screen_area", 100, {"screen_area": 100.0}, {"screen_area": 99.5}),
    ("max_screen_area", 100, {"screen_area": 99.5}, {"screen_area": 100.5}),
    ("program", ["0123abcd"], {"program": "0123abcd" + "9" * 56}, {"program": "0123abce" + "9" * 56}),
    ("pass", ["Solid Pass"], {"pass": "Solid Pass"}, {"pass": "Transparent"}),
    ("instances", [2, 15], {"instances": 15}, {"instances": 1}),
    ("draw_index", [3, 3], {"draw_index": 3}, {"draw_index": 4}),
    ("texture_image", ["89abcdef"], {"texture_image": "89abcdef01234567"}, {"texture_image": ""}),
], ids=lambda v: v if isinstance(v, str) else "")
def test_each_condition(tmp_path, field, value, inside, outside):
    toml = str(value).lower() if isinstance(value, (bool, int)) else str(value).replace("'", '"')
    s = rules(tmp_path, f"[[object]]\nid = 1\n{field} = {toml}\n")
    assert s.classify(draw(**inside)) == (1, "id 1")
    assert s.classify(draw(**outside)) == (None, "no rule")


@pytest.mark.parametrize("text, words", [
    ("[[object]]\nid = 1\nvertex_count = [5, 2]\n", "object[0].vertex_count: must be [MIN, MAX]"),
    ("[[object]]\nid = 1\nbogus = 1\n", "object[0].bogus: unknown key"),
    ("[[object]]\nname = \"x\"\n", "object[0]: needs id"),
    ("[[object]]\nid = -1\n", "object[0].id: must be an integer in [0, 4294967295]"),
    ("[[object]]\nid = true\n", "object[0].id: must be an integer in"),
    ("[[object]]\nid = 4294967296\n", "object[0].id: must be an integer in"),
    ("[settings]\nup_axis = \"w\"\n", "settings.up_axis"),
    ("a = " + "[" * 3000 + "]" * 3000 + "\n", "nested too deep"),
    ("[[exclude]]\nprojection = \"fisheye\"\n", "exclude[0].projection"),
    ("[[object]]\nid = 1\ntexture = [\"a\"]\n", "object[0].texture"),
    ("[[object]]\nid = 1\ngroup_by = \"colour\"\n", "object[0].group_by"),
    ("[[object]]\nid = 1\nmin_screen_area = \"big\"\n", "object[0].min_screen_area"),
    ("[settings]\nspeed = 1\n", "settings.speed: unknown key"),
    ("settings = 1\n", "settings must be a table"),
    ("object = 1\n", "object must be an array of tables"),
    ("[camera]\n", "unknown table or key 'camera'"),
    ("[[object]\n", "rules.toml"),
    ("[[object]]\nid = 1\nprogram = [\"abc\"]\n", "object[0].program: must be a list of program digests"),
    ("[[object]]\nid = 1\nprogram = []\n", "object[0].program"),
    ("[[object]]\nid = 1\npass = [3]\n", "object[0].pass: must be a list of pass names"),
    ("[[object]]\nid = 1\ninstances = [3, 1]\n", "object[0].instances: must be [MIN, MAX]"),
    ("[[object]]\nid = 1\ngroup_instances = 1\n", "object[0].group_instances: must be true or false"),
    ("[[object]]\nid = 1\ntexture_image = [\"89ABCDEF\"]\n", "object[0].texture_image: must be a list"),
    ("[[exclude]]\nid = \"x\"\n", "exclude[0].id: an exclude rule gives no id"),
    # Every integer a rule takes is within what it can match (R16-12).
    ("[[object]]\nid = 1\ntexture = [-1]\n", "object[0].texture: must be a list of texture names (integers in "
     "[0, 4294967295])"),
    ("[[object]]\nid = 1\ntexture = [7, 4294967296]\n", "object[0].texture: must be a list of texture names"),
    ("[[object]]\nid = 1\ninstances = [0, 1180591620717411303424]\n",
     "object[0].instances: must be [MIN, MAX], integers in [0, 4294967295]"),
    ("[[object]]\nid = 1\ninstances = [0, 4294967296]\n", "object[0].instances: must be [MIN, MAX]"),
    ("[[object]]\nid = 1\nvertex_count = [1, 4294967296]\n", "object[0].vertex_count: must be [MIN, MAX]"),
    ("[[object]]\nid = 1\ndraw_index = [0, 4294967296]\n", "object[0].draw_index: must be [MIN, MAX]"),
    ("[[exclude]]\ncalls = [0, 9223372036854775808]\n",
     "exclude[0].calls: must be [MIN, MAX], integers in [0, 9223372036854775807]"),
    ("[[exclude]]\nframes = [0, 9223372036854775808]\n", "exclude[0].frames: must be [MIN, MAX]"),
], ids=["vertex_count", "unknown_key", "no_id", "negative_id", "bool_id", "id_past_u32", "up_axis", "deep", "projection", "texture", "group_by",
        "screen_area", "settings_key", "settings_type", "object_type", "unknown_table", "toml_syntax",
        "program_short", "program_empty", "pass_type", "instances_order", "group_instances_type",
        "texture_image_case", "exclude_id", "texture_negative", "texture_past_u32", "instances_2_70",
        "instances_past_u32", "vertex_count_past_u32", "draw_index_past_u32", "calls_past_u63", "frames_past_u63"])
def test_bad_rules_are_named(tmp_path, text, words):
    with pytest.raises(ConvertError) as e:
        rules(tmp_path, text)
    assert words in str(e.value) and "rules.toml" in str(e.value)


def test_the_largest_values_a_rule_may_name_are_taken(tmp_path):
    s = rules(tmp_path, "[[object]]\nid = 1\ntexture = [0, 4294967295]\ninstances = [0, 4294967295]\n"
                        "calls = [0, 9223372036854775807]\n")
    assert s.classify(draw(texture=4294967295, instances=7)) == (1, "id 1")


@pytest.mark.parametrize("line, parts", [
    ("x" + ".x" * 40000 + " = 1", 40001),                       # R16-7: 6.3 GB in tomllib
    ("[[object]]\nid = 1\ncalls" + ".c" * 64 + " = 1", 65),    # in an [[object]], on line 3
    ("[" + ".".join(["t"] * 65) + "]", 65),                      # a table header
    ("[[" + " . ".join(["o"] * 70) + "]]", 70),                  # an array-of-tables header, spaced
    ("x = {" + ".".join(['"a.b"'] * 65) + " = 1}", 65),          # quoted parts in an inline table
    ('x = """a\\"""b"""\n' + "k" + ".k" * 100 + " = 1", 101),  # after an escaped quote in a multi-line string
], ids=["key_40001", "in_object", "table_header", "array_header", "inline_table", "after_escaped_quotes"])
def test_a_key_of_too_many_dotted_parts_is_refused_before_tomllib(tmp_path, line, parts):
    """tomllib's work and memory grow with the square of a dotted key's parts
    (R16-7: 40,000 parts, an 80 KB file, took 6.3 GB and 24 s): a key of more
    than 64 parts is refused first, naming the file and its line."""
    with pytest.raises(ConvertError) as e:
        rules(tmp_path, line + "\n")
    lineno = line.count("\n") + 1
    assert str(e.value) == f"{tmp_path / 'rules.toml'}:{lineno}: a key of {parts} dotted parts, more than 64"


def test_dots_in_strings_comments_and_keys_within_the_limit_are_not_counted(tmp_path):
    k = ".".join(["a"] * 100)
    q3, a3 = '"' * 3, "'" * 3
    s = rules(tmp_path, f"# {k}\n[[object]]\nname = \"{k}\"\nid = 1\n"
                        f"pass = ['{k}', {a3}\n{k}{a3}, {q3}{k}\n{k}{q3}]\n[settings]\ntrack_radius = 1.5\n")
    assert s.rules[0][1]["name"] == k and s.rules[0][1]["pass"] == [k, k, k + "\n" + k]
    # 64 parts, the first quoted with 99 dots of its own: taken (tomllib reads it).
    from rbcd.cli import check_toml_keys
    text = f'"{k}".{".".join(["b"] * 63)} = 1\n'
    assert check_toml_keys("f", text) == text


# The key guard as it was first written: one regular expression whose strings
# and dotted runs are repetitions of a group (R17-9: 150 bytes of memory a
# character). It finds the keys of a TOML text as the guard must.
_PART = r"""[A-Za-z0-9_-]+|"(?:[^"\\\n]|\\.)*"?|'[^'\n]*'?"""
_KEYS = (r'"""(?:\\[\s\S]|[^\\])*?(?:"""|\Z)|' + r"'''[\s\S]*?(?:'''|\Z)|#[^\n]*|"
         + r"(?P<key>(?:%s)(?:[ \t]*\.[ \t]*(?:%s))*)" % (_PART, _PART))


def reference_keys(text):
    keys = []
    for m in re.finditer(_KEYS, text):
        key = m.group("key")
        if key is not None:
            parts = len(re.findall(_PART, key)) if key.count(".") >= 64 else None
            keys.append((m.start(), m.end(), parts))
    return keys


Q3, A3 = '"' * 3, "'" * 3
TRICKY = [
    "", "a", "a.b.c = 1\n", "a . b\t.\tc = 1", "a. = 1", "a .\n b", '"a.b".c = 1', "'a.b'.c = 1",
    '"a\\".b".c', '"a\\\\".b', '"a\\\\\\".b".c', '"a\\\\\\\\"."b"', '"a\\\nb".c', '"a\\', '"a\\\\', '"a', "'a",
    '"a\n.b', 'x = "\\"" # "\na.b', "# a.b\nc.d", "#\\\na.b", '\\"a.b"', '\\\\"a.b".c', "\\'a.b'.c",
    "'a\\'.b", f"{Q3}a.b{Q3}.c", f"{Q3}a\\{Q3}b{Q3}.c", f"{Q3}a\\\\{Q3}.b", f'{Q3}a\\\n{Q3}x.y',
    f"{Q3}a{Q3}{Q3}.b", f'{Q3}a"""""c.d', f"{Q3}a.b", f"{Q3}a.b\\", f"{Q3}a.b\\\\", f"x{Q3}\n\\{Q3}\nc.d\\",
    f"{Q3}\n\\{Q3}\n\\{Q3}\n\\", f'{Q3}"a.b"\\', f"{A3}a.b{A3}.c", f"{A3}a\\{A3}.c", f"{A3}a.b",
    '"\\"\\"\\"".b', '"a\x00\\\x00".b', "\u00e9.a.\u00e9", "a" + ".a" * 63, "a" + ".a" * 64,
    "a" + " . a" * 70 + ".", '"x.y".' * 70 + "z", f"{Q3}a\\" + "\n.b" * 70, "a" + ".a" * 5000 + ' "b"',
]


@pytest.mark.parametrize("text", TRICKY, ids=[f"text{i}" for i in range(len(TRICKY))])
def test_the_key_guard_finds_the_keys_its_first_regular_expression_found(text):
    """The guard reads strings and dotted runs with little memory (R17-9)
    and finds the same runs of dotted parts, with the same counts, as the
    first expression did: escapes, multi-line strings closed, open or left
    with a lone backslash at the end, comments, long and spaced keys."""
    from rbcd.cli import _toml_keys
    assert list(_toml_keys(text)) == reference_keys(text)


def guard_child(texts):
    '''What check_toml_keys says of each text (Python expressions of n, 1
    MiB, q, a double quote, and q3, three) in a python of its own, and how
    much that python's maximum resident set grew (KB) meanwhile.'''
    child = (r'''
import resource
from rbcd.cli import check_toml_keys, UsageError
n, q, q3 = 1 << 20, '"', '"' * 3
texts = [%s]
base = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
for t in texts:
    try:
        check_toml_keys("f", t)
    except UsageError as e:
        print(e)
print(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss - base)
''' % ", ".join(texts))
    r = subprocess.run([sys.executable, "-c", child], capture_output=True, text=True, timeout=30,
                       env={"PATH": "/usr/bin:/bin", "PYTHONPATH": os.pathsep.join(sys.path)})
    assert r.returncode == 0, r.stderr
    *said, grown_kb = r.stdout.splitlines()
    return said, int(grown_kb)


def test_the_key_guard_keeps_its_memory_small():
    '''R17-9: a 1 MiB string, a 1 MiB multi-line one of escapes and a key
    of 1 MiB of dotted parts each took the guard 80-160 MB (re's stack
    holding a frame for each repetition of a group); they take almost
    nothing now, and the key is still counted and refused.'''
    said, grown_kb = guard_child([r'''"x = " + q + "a" * n + q + "\n"''',
                                  r'''"x = " + q3 + '\\"' * (n // 2) + q3 + "\n"''',
                                  r'''"a" + ".a" * (n // 2) + " = 1\n"'''])
    assert said == ["f:1: a key of 524289 dotted parts, more than 64"]
    assert grown_kb < 20 * 1024, f"the guard's memory grew by {grown_kb} KB"


def test_a_multi_line_string_left_open_is_read_to_the_end_once():
    '''A multi-line basic string left open, with a lone backslash at the
    text's end, fails; reopened after a backslash on each line (1 MiB), it
    was read to the end once a line (hours); now once.'''
    said, _ = guard_child([r'''q3 + "\n" + ("\\" + q3 + "\n") * (n // 5) + "\\"'''])
    assert said == []


@pytest.mark.parametrize("char", ["\u202e", "\u2066", "\u200b", "\u00ad", "\ufeff", "\U000e0001", "\ue000",
                                  "\U0010ffff", "\u0378"],
                         ids=["U+202E", "U+2066", "U+200B", "U+00AD", "U+FEFF", "U+E0001", "U+E000", "U+10FFFF",
                              "U+0378"])
def test_format_and_invisible_characters_are_escaped_in_messages(tmp_path, char):
    """A selection key holding U+202E RIGHT-TO-LEFT OVERRIDE (which makes a
    terminal show the rest of the line reversed: R16-11), another Unicode
    format, bidirectional or invisible character, or a private-use or
    unassigned one, is written as the \\xNN of its UTF-8 bytes, as controls
    are; letters of other scripts and spaces stay as they are."""
    p = tmp_path / "rules.toml"
    p.write_text('"\\u001b[2J\\U%08xevil\u0130 \u00a0x" = 1\n' % ord(char), encoding="utf-8")
    with pytest.raises(ConvertError) as e:
        Selection(str(p))
    msg = str(e.value)
    assert "'\\x1b[2J" + "".join(f"\\x{b:02x}" for b in char.encode()) + "evil\u0130 \u00a0x'" in msg, msg
    assert all(c.isprintable() or c == "\u00a0" for c in msg), msg


def test_unreadable_and_oversized_rules(tmp_path):
    with pytest.raises(ConvertError, match="cannot read"):
        Selection(str(tmp_path / "none.toml"))
    big = tmp_path / "big.toml"
    big.write_text("#" * (1 << 20) + "\n")
    with pytest.raises(ConvertError, match="larger than 1048576 bytes"):
        Selection(str(big))


def at(x, y, z):
    m = np.identity(4)
    m[0:3, 3] = (x, y, z)
    return m


def test_entities_join_parts_and_keep_their_ids_across_frames():
    t = EntityTracker({"up_axis": "z", "part_horizontal": 16, "part_vertical": 64, "track_radius": 48})
    t.begin_frame()
    legs = t.id_for(at(0, 0, 0), None, 1)
    torso = t.id_for(at(5, 0, 40), None, 2)            # 5 across, 40 up: the same entity
    other = t.id_for(at(200, 0, 0), None, 3)
    assert (legs, torso, other) == (1, 1, 2), "parts within reach join; a far one is the next free id"
    assert t.id_for(at(0, 0, 0), None, 4) == 1, "one model-view, one part"
    t.begin_frame()
    # Both moved by less than track_radius; listed in the other order.
    assert t.id_for(at(230, 0, 0), None, 5) == 2
    assert t.id_for(at(20, 0, 0), None, 6) == 1
    assert t.id_for(at(-500, 0, 0), None, 7) == 3, "a newcomer takes an id no entity of either frame holds"


def test_the_view_is_undone_without_its_scale():
    t = EntityTracker({"up_axis": "y"})
    view = np.diag([10.0, 10.0, 10.0, 1.0])   # a sky box's scaled view (Neverball)
    view[0:3, 3] = (0, 0, -100)
    t.begin_frame()
    a = t.id_for(at(0, 0, -100), view, 1)
    b = t.id_for(at(30, 0, -100), view, 2)     # 30 eye units across: apart
    assert a != b, "distances stay in eye units"


def test_too_many_entities_and_bad_settings():
    t = EntityTracker({"first_entity_id": 5, "max_entity_id": 6})
    t.begin_frame()
    assert [t.id_for(at(1000 * i, 0, 0), None, i) for i in range(2)] == [5, 6]
    with pytest.raises(ConvertError, match=r"call 9: more than 2 entities in one frame"):
        t.id_for(at(5000, 0, 0), None, 9)
    for settings, words in (({"up_axis": "w"}, "settings.up_axis: must be"),
                            ({"first_entity_id": "a"}, "settings.first_entity_id: 'a' is not an integer"),
                            ({"first_entity_id": -1}, "settings.first_entity_id: -1 is outside"),
                            ({"max_entity_id": 1 << 32}, "settings.max_entity_id: 4294967296 is outside"),
                            ({"track_radius": float("nan")}, "settings.track_radius: nan is not finite"),
                            ({"first_entity_id": 9, "max_entity_id": 3}, "first_entity_id is above")):
        with pytest.raises(ConvertError, match=words):
            Selection.check_settings("r.toml", settings)


def test_the_shipped_rules_read():
    """Every selection file in workloads/games/ reads (the games' rules)."""
    import glob
    from conftest import ROOT
    files = sorted(glob.glob(f"{ROOT}/workloads/games/*-select.toml"))
    assert {"openarena-select.toml", "neverball-select.toml", "supertuxkart-select.toml"} <= \
        {f.rsplit("/", 1)[1] for f in files}
    for f in files:
        assert Selection(f).rules, f"{f}: no rule"


@pytest.mark.parametrize("text, words", [
    ('[[object]]\ngroup_by = "projection"\n', 'object[0].group_by: must be "modelview" or "instance_origin"'),
    ('[[object]]\nid = 3\ngroup_by = "modelview"\n', "object[0]: id and group_by both given"),
    ("[[exclude]]\nid = 5\n", "exclude[0].id: an exclude rule gives no id"),
    ('[[exclude]]\ngroup_by = "modelview"\n', "exclude[0].group_by: an exclude rule gives no id"),
    ("[[object]]\nid = 3\nmax_screen_area = -1\n", "object[0].max_screen_area: -1 is outside [0.0, None]"),
    ("[[object]]\nid = 3\nmin_screen_area = 9\nmax_screen_area = 4\n", "min_screen_area is above max_screen_area"),
], ids=["unknown_group_by", "id_and_group_by", "exclude_id", "exclude_group_by", "negative_area", "areas_reversed"])
def test_rules_that_match_nothing_or_name_no_id_are_refused(tmp_path, text, words):
    """A rule whose keys contradict each other or cannot match is the
    file's error, named, not taken silently (round 22's R22-9: a negative
    max_screen_area, an exclude rule's id and an id beside group_by had
    been accepted without a word; an unknown group_by said the rule needed
    an id)."""
    p = tmp_path / "s.toml"
    p.write_text(text)
    with pytest.raises(ConvertError) as e:
        Selection(str(p))
    assert words in str(e.value), str(e.value)

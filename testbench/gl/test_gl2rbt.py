"""scripts/rbcd-gl2rbt on captures of testbench/gl/gl_boxes.c (docs/gl-capture.md;
gl_captures.py says what the captures draw). Each test reads the captures
test_gl_capture.py made and is skipped, saying so, without them."""
import json
import os
import re

import pytest

from conftest import program
from gl_captures import DEPTH_MAX, Converter, capture_path, pairs_per_frame, read_trace, run


@pytest.fixture
def gl(tmp_path):
    return Converter(tmp_path)


def test_convert(gl):
    path, r = gl.convert("--summary", gl.path("s.jsonl"))
    frames, tiles = read_trace(path)
    assert sorted(frames) == [0, 1, 2], f"frames {sorted(frames)}"
    with open(gl.path("s.jsonl")) as f:
        summary = [json.loads(l) for l in f]
    # Frame 0: (400 + 400 + 100) front fragments, as many back (c); 1600 + 32 other.
    s0, s1, s2 = summary
    assert (s0["fragments"], s0["culled"], s0["other"], s0["objects"]) == (1800, 900, 1632, [1, 2, 3]), \
        f"frame 0 figures {s0}"
    # Frame 1: (1600 + 100 + 100) x 2; the GL_EQUAL pass of box 3 is other work (its 100 front fragments).
    assert (s1["fragments"], s1["culled"], s1["other"], s1["objects"]) == (3600, 1800, 1732, [1, 2, 3]), \
        f"frame 1 figures {s1}"
    # Frame 2: closed objects: every covered pixel has a front and a back fragment.
    assert s2["objects"] == [1, 2, 4] and s2["fragments"] == 2 * s2["culled"] and s2["other"] == 32, \
        f"frame 2 figures {s2}"
    for s, f in zip(summary, sorted(frames)):
        assert sum(len(v) for v in frames[f].values()) == s["fragments"], f"frame {f}: summary and trace differ"
        assert all(c == (fc == "B") for v in frames[f].values() for _, _, fc, c in v), \
            f"frame {f}: a back face not tagged c, or a front face tagged"
    # Pixel (10, 80) (window y 15) lies in box 1 only: its faces at eye z -10 and -20,
    # window depth 0.5 + 0.5 * 0.01 * |z| of 2^24 - 1.
    got = sorted(frames[0][(10, 80)])
    want = sorted([(round(0.55 * DEPTH_MAX), 1, "F", False), (round(0.60 * DEPTH_MAX), 1, "B", True)])
    assert got == want, f"pixel (10, 80) of frame 0: {got}, expected {want}"
    assert (27, 80) in frames[0] and (28, 80) not in frames[0] and (8, 87) in frames[0] and (8, 88) not in frames[0], \
        "box 1's edges are off by a pixel"
    # Tiles say how many primitives they set up, and the rest of the GPU's work as o records.
    assert all("prims=" in t and "cprims=" in t for _, t in tiles), "a tile without prims= or cprims="
    # Gzip output when the name ends in .gz: the same trace.
    gz, _ = gl.convert(out="boxes.rbt.gz")
    with open(gz, "rb") as f:
        assert f.read(2) == b"\x1f\x8b", "a .gz output is not gzip"
    assert read_trace(gz)[0] == frames, "the .gz output differs from the plain one"
    assert "collisionable objects" in r.stdout, f"no summary line: {r.stdout!r}"


def test_pairs(gl):
    path, _ = gl.convert()
    hits = pairs_per_frame(path, gl.path("c.txt"))
    # Overlap, one inside another, and a sphere against a box; box 3 and
    # frame 2's box 2 are apart from everything.
    assert hits[0] == {(1, 2): 8 * 12}, f"frame 0 pairs {hits[0]}"
    assert hits[1] == {(1, 2): 10 * 10}, f"frame 1 pairs {hits[1]}"
    assert set(hits[2]) == {(1, 4)}, f"frame 2 pairs {hits[2]}"


def test_mesa_check_bounds_the_replay_window(gl):
    """glretrace grows its window to every viewport's far corner: past 2^24
    pixels (4100 x 4100 here) the check is refused naming the call, before
    glretrace runs (a viewport of 40,000 x 40,000 had taken it to 5 GB)."""
    r = gl(capture_path("wide"), "--check-depth")
    lines = r.stderr.strip().splitlines()
    assert r.returncode == 2 and len(lines) == 1 and "glViewport would make glretrace's window 4100 x 4100" \
        in lines[0], lines
    assert r.stdout == "" and os.listdir(gl.tmp) == [], "the check ran, or left files"


def test_mesa(gl):
    r = gl(capture_path(), "--check-depth")
    assert r.returncode == 0, f"--check-depth failed ({r.returncode}): {r.stdout}{r.stderr}"
    m = re.search(r"agreement: ([0-9.]+)% of (\d+) covered pixels in (\d+) frames", r.stdout)
    assert m and float(m.group(1)) >= 99.0 and int(m.group(2)) > 1000 and int(m.group(3)) == 2, \
        f"agreement below 99% or too little checked: {r.stdout}"
    # The second comparison: llvmpipe's float32 arithmetic replayed on the
    # converter's vertices, per frame and in all, over the same pixels.
    per_frame = re.findall(r"^  with llvmpipe's arithmetic on the converter's geometry: ([0-9.]+)% of (\d+) "
                           r"covered pixels agree$", r.stdout, re.M)
    lp = re.search(r"^agreement with llvmpipe's arithmetic on the converter's geometry: ([0-9.]+)% of (\d+) "
                   r"covered pixels$", r.stdout, re.M)
    assert len(per_frame) == 2 and lp and float(lp.group(1)) >= 99.0 and lp.group(2) == m.group(2), r.stdout


def test_mesa_check_of_a_capture_whose_only_frame_is_frame_0(gl):
    """glretrace replays a capture's first frame wrongly at times, so frame
    0 is checked only when asked for alone (--frames 0:0): a capture of one
    frame is refused saying so and how (round 33's F2: "no selected frame
    draws with the depth test on", which it does)."""
    one = gl.path("one.trace")
    r = run(["apitrace", "trim", "--frames=0", "-o", one, capture_path()])
    assert r.returncode == 0 and os.path.exists(one), r.stderr
    r = gl(one, "--check-depth")
    lines = r.stderr.strip().splitlines()
    assert r.returncode == 2 and len(lines) == 1 and "only frame 0 draws with the depth test on" in lines[0] \
        and "--frames 0:0 checks it all the same" in lines[0], (r.returncode, lines)
    r = gl(one, "--check-depth", "--frames", "0:0")
    assert re.search(r"^agreement: [0-9.]+% of \d+ covered pixels in 1 frames", r.stdout, re.M), r.stdout + r.stderr


def test_mesa_check_leaves_out_frames_read_through_another_window(gl):
    """Frames 0 and 1 drawn with a 16 x 16 window as the context's read
    drawable (glXMakeContextCurrent), frame 2 reading its own: the trace is
    the plain capture's, and the check leaves the first two frames out,
    saying so, since Mesa's replay reads the window's depth through the
    read drawable (round 15's R15-4: "0.00% agree", exit 1, a false alarm);
    frame 2 is checked and agrees."""
    path, _ = gl.convert(name="readother", out="readother.rbt")
    plain, _ = gl.convert()
    with open(path, "rb") as a, open(plain, "rb") as b:
        assert a.read() == b.read(), "the read drawable changed the trace"
    r = gl(capture_path("readother"), "--check-depth")
    assert r.returncode == 0, f"--check-depth failed ({r.returncode}): {r.stdout}{r.stderr}"
    assert re.search(r"^2 frames not checked: their last depth-tested draw's context reads from another window "
                     r"than it draws into, .* \(the first, frame 0\)$", r.stdout, re.M), r.stdout
    m = re.search(r"^agreement: ([0-9.]+)% of (\d+) covered pixels in 1 frames", r.stdout, re.M)
    assert m and float(m.group(1)) >= 99.0 and int(m.group(2)) > 1000, r.stdout
    assert re.search(r"^frame 2 \(call \d+\): ", r.stdout, re.M), r.stdout


def test_glsl_programs_of_the_compatibility_profile(gl):
    """gl_boxes' glsl capture: its array draws under GLSL 1.20 programs
    reading gl_ModelViewProjectionMatrix, ftransform() and gl_Vertex (from
    the vertex array, and in frame 2 from generic attribute 0) convert into
    the plain capture's trace, byte for byte (they had been refused); its
    reduced capture gives the same bytes; Mesa's replay agrees."""
    path, _ = gl.convert("--reduced-out", gl.path("glsl.calls.xz"), name="glsl", out="glsl.rbt")
    plain, _ = gl.convert()
    with open(path, "rb") as a, open(plain, "rb") as b:
        assert a.read() == b.read(), "the programs changed the trace"
    r = gl(gl.path("glsl.calls.xz"), "-o", gl.path("reduced.rbt"))
    assert r.returncode == 0, r.stderr
    with open(path, "rb") as a, open(gl.path("reduced.rbt"), "rb") as b:
        assert a.read() == b.read(), "the reduced capture's trace differs"
    r = gl(capture_path("glsl"), "--check-depth")
    assert r.returncode == 0, f"--check-depth failed ({r.returncode}): {r.stdout}{r.stderr}"
    m = re.search(r"^agreement: ([0-9.]+)% of (\d+) covered pixels in 2 frames", r.stdout, re.M)
    assert m and float(m.group(1)) >= 99.0 and int(m.group(2)) > 1000, r.stdout


def test_refusals(gl):
    expect = {"nan": "not finite", "index": "reach past", "list": "glNewList",
              "shader": "program", "line": "GL_FILL"}
    for fault, words in expect.items():
        out = gl.path(f"{fault}.rbt")
        geo = gl.path(f"{fault}.geo")
        r = gl(capture_path(f"fault-{fault}"), "-o", out, "--geometry", geo)
        lines = r.stderr.strip().splitlines()
        assert r.returncode == 2, f"{fault}: exit {r.returncode}: {r.stderr.strip()}"
        assert len(lines) == 1 and re.search(r": call \d+: ", lines[0]) and words in lines[0], \
            f"{fault}: message {lines}"
        assert not os.path.exists(out) and not os.path.exists(geo), f"{fault}: an output was left"
        assert not [f for f in os.listdir(gl.tmp) if f.startswith(".")], f"{fault}: a temporary was left"
    # A capture cut short, and one with bytes overwritten.
    src = capture_path()
    with open(src, "rb") as f:
        data = f.read()
    for name, body in (("cut", data[: len(data) // 3]),
                       ("corrupt", data[:20000] + b"\xff" * 16 + data[20016:])):
        p = gl.path(name + ".trace")
        with open(p, "wb") as f:
            f.write(body)
        out = gl.path(name + ".rbt")
        r = gl(p, "-o", out)
        lines = r.stderr.strip().splitlines()
        assert r.returncode == 2 and len(lines) == 1 and "call" in lines[0], f"{name}: {r.returncode} {lines}"
        assert not os.path.exists(out), f"{name}: an output was left"


def test_gl_errors_ignored_as_mesa_ignores_them(gl):
    """An empty glOrtho (GL_INVALID_VALUE) and glPopMatrix on an empty stack
    (GL_STACK_UNDERFLOW) do nothing, in GL and here: the captures convert and
    their depth agrees with Mesa's replay."""
    for fault in ("ortho", "underflow"):
        cap = capture_path(f"fault-{fault}")
        r = gl(cap, "-o", gl.path(f"{fault}.rbt"))
        assert r.returncode == 0, f"{fault}: {r.stderr}"
        r = gl(cap, "--check-depth")
        m = re.search(r"agreement: ([0-9.]+)%", r.stdout)
        assert r.returncode == 0 and m and float(m.group(1)) >= 99.0, f"{fault}: {r.stdout}{r.stderr}"


def test_select(gl):
    """Selection rules for untagged draws: the floor of frame 0 (call
    range, vertex count) becomes object 9; a bad rules file is one line
    naming the key; --list-draws says what each draw became and why."""
    cap = capture_path()
    listing = gl(cap, "--list-draws", "0")
    assert listing.returncode == 0, f"--list-draws failed: {listing.stderr}"
    floor = [l for l in listing.stdout.splitlines() if "glDrawArrays" in l]
    assert len(floor) == 1 and "untagged" in floor[0], f"the floor's listing: {floor}"
    call = int(floor[0].split()[1])
    rules = gl.path("rules.toml")
    with open(rules, "w") as f:
        f.write(f'[[exclude]]\nname = "2D"\nprojection = "perspective"\n\n'
                f'[[object]]\nname = "floor"\nid = 9\ncalls = [{call}, {call}]\nvertex_count = [4, 4]\n')
    path, _ = gl.convert("--select", rules, "--summary", gl.path("s.jsonl"))
    with open(gl.path("s.jsonl")) as f:
        s0 = json.loads(f.readline())
    assert s0["objects"] == [1, 2, 3, 9] and s0["fragments"] == 1800 + 1600 and s0["other"] == 32, \
        f"the floor did not become object 9: {s0}"
    frames, _ = read_trace(path)
    assert frames[0][(100, 50)] == [(round(0.75 * DEPTH_MAX), 9, "F", False)], \
        f"the floor's fragment at (100, 50): {frames[0].get((100, 50))}"
    listing = gl(cap, "--list-draws", "0", "--select", rules, "--image", gl.path("f0.png"))
    floor = [l for l in listing.stdout.splitlines() if "glDrawArrays" in l]
    assert floor and floor[0].split()[-2:] == ["9", "floor"], f"the listing does not say floor: {floor}"
    with open(gl.path("f0.png"), "rb") as f:
        assert f.read(8) == b"\x89PNG\r\n\x1a\n", "--image wrote no PNG"
    for body, key in (('[[object]]\nid = 1\nvertex_count = [5, 2]\n', "vertex_count"),
                      ('[[object]]\nid = 1\nbogus = 1\n', "bogus"),
                      ('[[object]]\nname = "x"\n', "needs id"),
                      ('[[object]\n', "rules.toml")):
        with open(rules, "w") as f:
            f.write(body)
        out = gl.path("sel.rbt")
        r = gl(cap, "-o", out, "--select", rules)
        lines = r.stderr.strip().splitlines()
        assert r.returncode == 2 and len(lines) == 1 and key in lines[0] and "rules.toml" in lines[0], \
            f"rules {body!r}: {r.returncode} {lines}"
        assert not os.path.exists(out), "an output was left after a bad rules file"


def test_geometry(gl):
    """--geometry through rbcd-cpucd: the ground truth has each frame's
    pairs (overlap, one inside another, sphere and box), on screen."""
    cpucd = program("rbcd-cpucd")   # skipped without it: Bullet and FCL, scripts/setup.sh --eval
    geo = gl.path("boxes.geo")
    gl.convert("--geometry", geo)
    csv_path = gl.path("pairs.csv")
    r = run([cpucd, "--geometry", geo, "--pairs", csv_path, "-q"])
    assert r.returncode == 0, f"rbcd-cpucd failed: {r.stderr.strip()}"
    with open(csv_path) as f:
        rows = [l.strip().split(",") for l in f][1:]
    exact = {(int(r[0]), int(r[1]), int(r[2])): (r[5], r[6], r[7]) for r in rows if r[5] == "1"}
    assert exact == {(0, 1, 2): ("1", "0", "1"), (1, 1, 2): ("1", "1", "1"), (2, 1, 4): ("1", "0", "1")}, \
        f"ground truth pairs (frame, a, b): (exact, contained, on_screen) = {exact}"
    # An object scaled to a point (object 9 in frame 1 of the "point"
    # capture) has no surface: no fragment, no mesh record, and the file
    # stays readable (rbcd-cpucd refuses a mesh of fewer than 3 vertices).
    geo9 = gl.path("point.geo")
    path, _ = gl.convert("--geometry", geo9, name="point", out="point.rbt")
    with open(geo9) as f:
        meshes = [l.split()[1] for l in f if l.startswith("mesh ")]
    assert "9" not in meshes and {"1", "2", "3"} <= set(meshes), \
        f"mesh ids of the point capture: {sorted(set(meshes))}"
    frames9, _ = read_trace(path)
    assert all(obj != 9 for pixels in frames9.values() for frags in pixels.values() for _, obj, _, _ in frags), \
        "object 9 has fragments"
    r = run([cpucd, "--geometry", geo9, "--pairs", gl.path("p9.csv"), "-q"])
    assert r.returncode == 0, f"rbcd-cpucd on the point capture's geometry: {r.stderr.strip()}"


def test_frames(gl):
    whole, _ = gl.convert()
    part, _ = gl.convert("--frames", "1:2", out="part.rbt")
    a, b = read_trace(whole)[0], read_trace(part)[0]
    assert sorted(b) == [0, 1] and b[0] == a[1] and b[1] == a[2], \
        "--frames 1:2 is not frames 1 and 2, renumbered"
    last, _ = gl.convert("--frames", "2:", out="last.rbt")
    assert read_trace(last)[0] == {0: a[2]}, "--frames 2: is not the last frame"


def test_reduced(gl):
    """--reduced-out: the reduced capture converts into the same trace and
    geometry as the capture (all frames and a range), is a fraction of its
    size, and a damaged one is refused in one line."""
    red = gl.path("boxes.calls.xz")
    gl.convert("--reduced-out", red)
    for extra, tag in (([], "all"), (["--frames", "1:2"], "1:2")):
        a_path, _ = gl.convert(*extra, "--geometry", gl.path(f"c-{tag}.geo"), out=f"c-{tag}.rbt")
        r = gl(red, "-o", gl.path(f"r-{tag}.rbt"),
                        "--geometry", gl.path(f"r-{tag}.geo"), *extra)
        assert r.returncode == 0, f"the reduced capture does not convert: {r.stderr.strip()}"
        for ext in ("rbt", "geo"):
            with open(gl.path(f"c-{tag}.{ext}"), "rb") as f1, \
                    open(gl.path(f"r-{tag}.{ext}"), "rb") as f2:
                assert f1.read() == f2.read(), f"frames {tag}: the reduced capture's .{ext} differs"
    size, full = os.path.getsize(red), os.path.getsize(capture_path())
    assert size < full / 2, f"the reduced capture is {size} bytes, the capture {full}"
    from rbcd.gl2rbt.reduced import REDUCED_HEADER, reduced_header, source_bytes
    assert reduced_header(red) == ("rbcd-reduced-capture", REDUCED_HEADER[1], full) and source_bytes(red) == full, \
        "the reduced capture names the capture's size, which its bounds take (R21-8)"
    with open(red, "rb") as f:
        data = f.read()
    bad = gl.path("bad.calls.xz")
    out = gl.path("bad.rbt")
    for body, words in ((data[:len(data) // 2], "reduced capture"),
                        (data[:-1], "reduced capture"),
                        (data[:6] + b"\0" * 40, "does not decode")):
        with open(bad, "wb") as f:
            f.write(body)
        r = gl(bad, "-o", out)
        lines = r.stderr.strip().splitlines()
        assert r.returncode == 2 and len(lines) == 1 and words in lines[0] and "bad.calls.xz" in lines[0], \
            f"a damaged reduced capture: exit {r.returncode}, {lines}"
        assert not os.path.exists(out), "an output was left after a damaged reduced capture"
    r = gl(red, "--check-depth")
    assert r.returncode == 2 and "reduced capture" in r.stderr, \
        f"--check-depth on a reduced capture: {r.stderr}"
    r = gl(red, "-o", out, "--reduced-out", gl.path("again.xz"))
    assert r.returncode == 2 and "already a reduced capture" in r.stderr, f"reducing twice: {r.stderr}"


def test_cli(gl):
    cap = capture_path()
    out = gl.path("x.rbt")
    cases = [
        ([cap, "-o", out, "--frames", "3:1"], "selects no frame"),
        ([cap, "-o", out, "--frames", "x"], "--frames"),
        ([cap, "-o", out, "--frames", "7:"], "has 3 frames"),
        ([cap, "-o", out, "--depth-bits", "0"], "--depth-bits"),
        ([cap, "-o", cap], "is also the capture"),
        ([cap], "-o OUT is required"),
        ([gl.tmp, "-o", out], "not a regular file"),
        ([gl.path("none.trace"), "-o", out], "cannot open"),
        ([cap, "-o", gl.path("no", "x.rbt")], "cannot create"),
        ([cap, "-o", out, "--select", gl.path("none.toml")], "cannot read"),
    ]
    for args, words in cases:
        r = gl(*args)
        lines = r.stderr.strip().splitlines()
        assert r.returncode == 2 and len(lines) == 1 and words in lines[0], \
            f"{args[1:]}: exit {r.returncode}, {lines}"
        assert not os.path.exists(out), f"{args[1:]}: an output was left"
    left = [d for d in os.listdir(gl.tmp) if d.startswith("rbcd-gl2rbt")]
    assert not left, f"temporary directories left by the refusals: {left}"
    with open(cap, "rb") as f:
        before = f.read()
    gl(cap, "-o", cap)
    with open(cap, "rb") as f:
        assert f.read() == before, "the capture was touched"

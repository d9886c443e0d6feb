"""The shader path of scripts/rbcd-gl2rbt on captures of testbench/gl/gl_shaders.c,
a GL 3.3 core program of our own (docs/gl-capture.md, "The shader path").

What gl_shaders draws, 128 x 96, a uniform block's orthographic projection
(0, 128, 0, 96, -100, 100) (window y up, screen rows down: row = 95 - y):
  a depth-only pass into a 64 x 64 framebuffer object first (box 1 again,
  tagged): not the camera pass, left out;
  frame 0: box 1 [8,28]x[8,28]x[-20,-10] (glDrawElements, a vertex array
           object reading the cube at an offset), box 2 [20,40]x[16,36]x[-15,-5]
           (glDrawElementsBaseVertex), boxes 3 and 4 as two instances of one
           glDrawElementsInstancedBaseVertex, [60,70]x[8,18]x[-10,-5] and
           [90,100]x[8,18] (per-instance offsets, divisor 1; object 3 + i);
           a 40 x 40 floor [0,40]x[40,80] at z = -50 of GL_SHORT positions
           written through glMapBufferRange, untagged;
  frame 1: the view (glBufferSubData into the block) moves everything 4 up
           and box 4's offset (glBufferSubData into the instance buffer)
           moves it 10 more right, [100,110]x[12,22]; box 1 through
           glDrawRangeElements, box 2 as triangle strips cut by primitive
           restart; box 1 drawn by a second program whose fragment shader
           can discard and writes gl_FragDepth (changing no fragment).
Face-on boxes give width x height front fragments and as many back ones (c:
culling is on): 400 + 400 + 100 + 100 front fragments a frame, the floor
1,600 other fragments; boxes 1 and 2 overlap on 8 x 12 pixels.
"""
import json
import os
import re
import shutil
import signal
import subprocess
import time

import pytest

from conftest import program
from gl_captures import (DEPTH_MAX, GL2RBT, SHADER_FAULTS, Converter, capture_path, pairs_per_frame, read_trace,
                         run)


@pytest.fixture
def gl(tmp_path):
    return Converter(tmp_path)


def convert(gl, *extra, out="shaders.rbt"):
    return gl.convert(*extra, name="shaders", out=out)


def test_convert(gl):
    path, r = convert(gl, "--summary", gl.path("s.jsonl"))
    frames, tiles = read_trace(path)
    assert sorted(frames) == [0, 1], f"frames {sorted(frames)}"
    with open(gl.path("s.jsonl")) as f:
        summary = [json.loads(line) for line in f]
    for s in summary:
        assert (s["fragments"], s["culled"], s["other"], s["objects"]) == (2000, 1000, 1600, [1, 2, 3, 4]), \
            f"frame {s['frame']}: the depth-only pass left in, or a draw lost: {s}"
        assert s["draws"] == 5, f"frame {s['frame']}: five camera-pass draw records (box 3's two instances)"
    effects = [tuple(s[k] for k in ("discard_draws", "discard_collisionable", "frag_depth_draws",
                                    "frag_depth_collisionable")) for s in summary]
    assert effects == [(0, 0, 0, 0), (1, 1, 1, 1)], f"draws under discard and gl_FragDepth per frame: {effects}"
    assert "can discard: 1 (1 collisionable); writing gl_FragDepth: 1 (1 collisionable)" in r.stdout
    for f in frames:
        assert all(c == (fc == "B") for v in frames[f].values() for _, _, fc, c in v), \
            f"frame {f}: a back face not tagged c, or a front face tagged"
    # Pixel (10, 80), window y 15: box 1 only, faces at eye z -10 and -20, in both frames.
    want = sorted([(round(0.55 * DEPTH_MAX), 1, "F", False), (round(0.60 * DEPTH_MAX), 1, "B", True)])
    for f in (0, 1):
        assert sorted(frames[f][(10, 80)]) == want, f"pixel (10, 80) of frame {f}: {frames[f].get((10, 80))}"
    # The instances: box 4 where its offset put it in each frame.
    assert {o for _, o, _, _ in frames[0][(95, 85)]} == {4} and (95, 85) not in frames[1], \
        "box 4 of frame 0 (instance 1 of object 3)"
    assert {o for _, o, _, _ in frames[1][(105, 80)]} == {4}, "box 4 moved by the instance buffer's update"
    # Box 1's edges, frame 0: columns 8..27, window rows 8..27 (screen rows 68..87).
    assert (27, 80) in frames[0] and (28, 80) not in frames[0] and (8, 87) in frames[0] and (8, 88) not in frames[0]
    # The floor (z = -50: depth 0.75) is other work, in o runs: no f records of its own.
    assert (5, 30) not in frames[0], "the floor became fragments of an object"
    assert "2 frames" in r.stdout and "collisionable objects" in r.stdout


def test_pairs(gl):
    path, _ = convert(gl)
    hits = pairs_per_frame(path, gl.path("c.txt"))
    assert hits == {0: {(1, 2): 8 * 12}, 1: {(1, 2): 8 * 12}}, f"pairs per frame {hits}"


def test_mesa(gl):
    r = gl(capture_path("shaders"), "--check-depth")
    assert r.returncode == 0, f"--check-depth failed ({r.returncode}): {r.stdout}{r.stderr}"
    m = re.search(r"agreement: ([0-9.]+)% of (\d+) covered pixels in (\d+) frames", r.stdout)
    assert m and float(m.group(1)) >= 99.0 and int(m.group(2)) > 2000, \
        f"agreement below 99% or too little checked: {r.stdout}"
    # Box 1 of frame 1 is drawn under a fragment shader that can discard: its
    # pixels are checked as a bound (Mesa's depth at or behind ours).
    m = re.search(r"agreement: .*; consistent ([0-9.]+)%: .* on ([0-9.]+)% of those (\d+) ", r.stdout)
    assert m and float(m.group(1)) >= 99.0 and float(m.group(2)) == 100.0 and int(m.group(3)) > 100, r.stdout
    # The same against llvmpipe's arithmetic on the converter's vertices: the
    # shader path's clip coordinates are Mesa's own float32 outputs.
    lp = re.search(r"^agreement with llvmpipe's arithmetic on the converter's geometry: ([0-9.]+)% of (\d+) "
                   r"covered pixels; consistent ([0-9.]+)%: ([0-9.]+)% of the (\d+) outside", r.stdout, re.M)
    assert lp and float(lp.group(3)) >= 99.0 and float(lp.group(4)) == 100.0, r.stdout


def test_geometry(gl):
    """--geometry of a shader capture: normalized device coordinates under an
    identity view; rbcd-cpucd's ground truth has boxes 1 and 2 touching in
    both frames, nothing else."""
    cpucd = program("rbcd-cpucd")   # skipped without it: Bullet and FCL, scripts/setup.sh --eval
    geo = gl.path("shaders.geo")
    convert(gl, "--geometry", geo)
    with open(geo) as f:
        text = f.read()
    assert "view 1.0 0.0 0.0 0.0 0.0 1.0 0.0 0.0 0.0 0.0 1.0 0.0 0.0 0.0 0.0 1.0" in text
    assert sorted(set(re.findall(r"^mesh (\d+) ", text, re.M))) == ["1", "2", "3", "4"]
    pairs = gl.path("pairs.csv")
    r = run([cpucd, "--geometry", geo, "--pairs", pairs, "-q"])
    assert r.returncode == 0, f"rbcd-cpucd failed: {r.stderr.strip()}"
    with open(pairs) as f:
        rows = [line.strip().split(",") for line in f][1:]
    exact = {(int(r[0]), int(r[1]), int(r[2])) for r in rows if r[5] == "1"}
    assert exact == {(0, 1, 2), (1, 1, 2)}, f"ground truth pairs (frame, a, b): {exact}"


def test_reduced(gl):
    """The reduced capture keeps what the vertex stage needs (sources,
    buffers, uniforms) and converts into the same trace and geometry."""
    red = gl.path("shaders.calls.xz")
    a, _ = convert(gl, "--reduced-out", red, "--geometry", gl.path("a.geo"))
    r = gl(red, "-o", gl.path("b.rbt"), "--geometry", gl.path("b.geo"))
    assert r.returncode == 0, f"the reduced capture does not convert: {r.stderr.strip()}"
    for x, y in ((a, gl.path("b.rbt")), (gl.path("a.geo"), gl.path("b.geo"))):
        with open(x, "rb") as f1, open(y, "rb") as f2:
            assert f1.read() == f2.read(), f"{os.path.basename(y)} differs from the capture's"
    assert os.path.getsize(red) < os.path.getsize(capture_path("shaders")) / 4


def test_list_draws(gl):
    r = gl(capture_path("shaders"), "--list-draws", "0", "--image", gl.path("f0.png"))
    assert r.returncode == 0, r.stderr
    rows = [line for line in r.stdout.splitlines() if re.match(r"\s*\d+ +\d+ ", line)]
    objects = [line.split()[-3 if line.endswith("debug group") else -2] for line in rows]
    assert objects == ["1", "2", "3", "4", "-"], f"--list-draws of frame 0: {r.stdout}"
    assert all(" ortho " in line for line in rows), "clip-space w of 1: an orthographic projection"
    with open(gl.path("f0.png"), "rb") as f:
        assert f.read(8) == b"\x89PNG\r\n\x1a\n"


def test_select_by_shader_state(gl):
    """Selection rules on shader state: the floor (untagged) chosen by its
    program's digest, its vertex count and its pass name (the application's
    glDebugMessageInsert) becomes object 20; --list-draws shows the digest
    and the passes."""
    cap = capture_path("shaders")
    listing = gl(cap, "--list-draws", "0")
    assert listing.returncode == 0, listing.stderr
    floor = [line for line in listing.stdout.splitlines() if "glDrawArrays" in line]
    assert len(floor) == 1 and floor[0].split()[-1] == "untagged", floor
    digest = floor[0].split()[6]   # after the texture name and its image digest
    assert re.fullmatch(r"[0-9a-f]{8}", digest), floor
    assert "passes: from call" in listing.stdout and "'Floor pass'" in listing.stdout, listing.stdout
    rules = gl.path("rules.toml")
    with open(rules, "w") as f:
        f.write(f'[[object]]\nname = "floor"\nid = 20\nprogram = ["{digest}"]\nvertex_count = [4, 4]\n'
                f'pass = ["Floor pass"]\ninstances = [1, 1]\n')
    _, r = convert(gl, "--select", rules, "--summary", gl.path("s.jsonl"))
    with open(gl.path("s.jsonl")) as f:
        s0 = json.loads(f.readline())
    assert (s0["fragments"], s0["culled"], s0["other"], s0["objects"]) == (3600, 1000, 0, [1, 2, 3, 4, 20]), s0
    with open(rules, "w") as f:
        f.write('[[object]]\nid = 20\nprogram = ["XYZ"]\n')
    r = gl(cap, "-o", gl.path("x.rbt"), "--select", rules)
    assert r.returncode == 2 and "object[0].program" in r.stderr, r.stderr


@pytest.mark.parametrize("fault", ["texture", "rendered", "cube", "array", "separable", "image", "multisample", "default",
                                   "msimage", "msdepth", "geometry"])
def test_a_vertex_shader_reading_an_uploaded_or_a_rendered_texture(gl, fault):
    """The fault "texture": a vertex shader moves a triangle by a texel of
    a texture uploaded with glTexImage2D, in front of every box: Mesa runs
    it on the capture's image (the check agrees), and the reduced capture
    carries the image and gives the same bytes. The faults "rendered" (its
    texture rendered by a draw into a framebuffer object), "cube" (a cube
    map's texel) and "array" (layer 1 of a 2D array texture): the same
    fragments, the textures read back from Mesa's replay of the capture
    (they had been refused). The fault "separable": the "texture" fault's
    draw through a program pipeline of separable programs (they had been
    refused), "geometry" (the triangle moved by the texel in a geometry
    shader Mesa runs with the vertex shader; it had been refused), and "image" (the array's layer 1 read by imageLoad through an
    image unit, read back from Mesa's replay; refused until now) and
    "multisample" (sample 3 of a multisample texture whose other samples
    hold another texel: every sample read back, by a compute shader in the
    replay, and drawn into Mesa's copy one by one) and "default" (the
    default 3D texture, name 0, given an image: round 12's R12-6, read as
    no texture) and "msimage" (the multisample texture's sample 3 read by
    imageLoad through an image unit) and "msdepth" (a multisample depth
    texture's sample 3 through a swizzle that moves the depth to green:
    read back without the swizzle and given it again; round 14's R14-1
    stored the swizzled red as the depth): the same fragments."""
    cap = capture_path(f"shader-fault-{fault}")
    assert_moved_triangle(checked_and_reduced(gl, cap, 2000))


def test_a_seamless_cube_map_read_by_a_vertex_shader(gl):
    """The fault "cubeseam": a cube map filtered linearly near the +X face's
    edge with +Y under GL_TEXTURE_CUBE_MAP_SEAMLESS, so a quarter of +Y's
    texel moves the triangle too: Mesa's context is given the enable (round
    16's R16-1: ignored, +X's texel alone, the check 0.00%); the check
    agrees and the reduced capture gives the same bytes, which differ from
    the "cube" fault's (+X's texel alone)."""
    seam = checked_and_reduced(gl, capture_path("shader-fault-cubeseam"), 2000)
    plain = gl.path("plain.rbt")
    r = gl(capture_path("shader-fault-cube"), "-o", plain)
    assert r.returncode == 0, r.stderr
    with open(seam, "rb") as a, open(plain, "rb") as b:
        assert a.read() != b.read(), "the seamless read gave +X's texel alone"


def checked_and_reduced(gl, cap, pixels):
    """The capture's Mesa check at 99% or more of more than `pixels`
    covered pixels; its trace, the same bytes from its reduced capture."""
    r = gl(cap, "--check-depth")
    assert r.returncode == 0, f"--check-depth failed ({r.returncode}): {r.stdout}{r.stderr}"
    m = re.search(r"^agreement: ([0-9.]+)% of (\d+) covered pixels in (\d+) frames", r.stdout, re.M)
    assert m and float(m.group(1)) >= 99.0 and int(m.group(2)) > pixels, r.stdout
    a, b, red = gl.path("t.rbt"), gl.path("t2.rbt"), gl.path("t.xz")
    r = gl(cap, "-o", a, "--reduced-out", red)
    assert r.returncode == 0, r.stderr
    r = gl(red, "-o", b)
    assert r.returncode == 0, r.stderr
    with open(a, "rb") as fa, open(b, "rb") as fb:
        assert fa.read() == fb.read(), "the reduced capture converts differently"
    return a


def assert_moved_triangle(path):
    """Object 9, frame 1: the triangle (16, 24) (80, 24) (80, 72) in window
    coordinates (half of 64x48 pixels, rows 24 to 71, its hypotenuse
    leaving column 16 out) at window depth 0.25; none in frame 0."""
    frames, _ = read_trace(path)
    tri = {xy: [d for d, obj, *_ in frags if obj == 9] for xy, frags in frames[1].items()}
    tri = {xy: ds for xy, ds in tri.items() if ds}
    assert len(tri) == 32 * 48 and min(x for x, _ in tri) == 17 and max(x for x, _ in tri) == 79, len(tri)
    assert {y for _, y in tri} == set(range(24, 72))
    assert all(abs(d - DEPTH_MAX / 4) <= 1 for ds in tri.values() for d in ds)
    assert not any(9 in [obj for _, obj, *_ in frags] for frags in frames[0].values())


@pytest.mark.parametrize("broken", ["no glretrace", "no library", "replay ends", "replay killed", "replay terminated",
                                    "replay stopped"])
def test_a_rendered_texture_mesa_s_replay_cannot_give(gl, broken, tmp_path):
    """Without glretrace or the readback library beside rbcd-gl-raster (a
    tool missing: exit 1), or with a replay that stops before the draw (a
    glretrace that exits at once: exit 2; one killed, terminated or stopped
    from outside: the tool's failure, exit 1, the capture named), the draw
    is refused in one line naming it, and nothing is left."""
    if broken == "no library":
        lone = tmp_path / "lone"
        lone.mkdir()
        shutil.copy(program("rbcd-gl-raster"), lone / "rbcd-gl-raster")
        gl.env["RBCD_GL_RASTER"] = str(lone / "rbcd-gl-raster")
    bin_dir = tmp_path / "bin"
    bin_dir.mkdir()
    for tool in os.listdir("/usr/bin"):   # every tool but glretrace (a PATH of /usr/bin's tools)
        if tool != "glretrace" or broken == "no library":
            (bin_dir / tool).symlink_to(os.path.join("/usr/bin", tool))
    if broken == "replay ends":
        (bin_dir / "glretrace").write_text("#!/bin/sh\necho 'glretrace: stopped early' >&2\nexit 1\n")
        (bin_dir / "glretrace").chmod(0o755)
    # (Killed, terminated or stopped from outside: round 15's R15-10 and
    # round 16's R16-9, blamed on the capture, exit 2.)
    signals = {"replay killed": "9", "replay terminated": "15", "replay stopped": "STOP"}
    if broken in signals:
        (bin_dir / "glretrace").write_text(f"#!/bin/sh\nkill -{signals[broken]} $$\n")
        (bin_dir / "glretrace").chmod(0o755)
    gl.env["PATH"] = str(bin_dir)
    out = gl.path("x.rbt")
    r = gl(capture_path("shader-fault-rendered"), "-o", out)
    lines = r.stderr.strip().splitlines()
    words, status = {"no glretrace": ("needs glretrace", 1), "no library": ("rbcd-texture-readback.so", 1),
                     "replay ends": ("stopped early", 2), "replay killed": ("was ended by signal 9", 1),
                     "replay terminated": ("was ended by signal 15", 1),
                     "replay stopped": ("was stopped (SIGSTOP) and did not go on", 1)}[broken]
    assert r.returncode == status and len(lines) == 1 and re.search(r": call \d+: glDrawArrays", lines[0]) \
        and words in lines[0], lines
    if status == 1 and broken.startswith("replay"):
        assert capture_path("shader-fault-rendered") in lines[0], lines
    assert not os.path.exists(out)
    assert not [f for f in os.listdir(gl.tmp) if f.startswith(("rbcd-gl2rbt", "."))], os.listdir(gl.tmp)


@pytest.mark.parametrize("sig", [signal.SIGKILL, signal.SIGSEGV], ids=["kill", "segv"])
def test_apitrace_ended_by_a_signal_is_not_the_capture_s_fault(gl, tmp_path, sig):
    """apitrace's reader killed from outside (SIGKILL: the kernel out of
    memory) part way through the capture: a tool's failure in one line,
    exit 1, no output, not "the capture does not decode", exit 2 (round
    14's R14-14); it had been taken for a truncated capture. A crash
    (SIGSEGV: apitrace's reader on overwritten bytes) is the capture's.
    The fake apitrace gives the first 4 KB of the real one's output, then
    dies."""
    real = shutil.which("apitrace")
    bin_dir = tmp_path / "bin"
    bin_dir.mkdir()
    (bin_dir / "apitrace").write_text(f"#!/bin/sh\n{real} \"$@\" | head -c 4096\nkill -{int(sig)} $$\n")
    (bin_dir / "apitrace").chmod(0o755)
    gl.env["PATH"] = f"{bin_dir}:{gl.env['PATH']}"
    out = gl.path("k.rbt")
    r = gl(capture_path("shaders"), "-o", out)
    lines = r.stderr.strip().splitlines()
    if sig == signal.SIGKILL:
        assert r.returncode == 1 and len(lines) == 1 and "was ended by signal 9" in lines[0], lines
    else:
        assert r.returncode == 2 and len(lines) == 1 and "apitrace crashed on it: signal 11" in lines[0], lines
    assert not os.path.exists(out)


def test_a_program_that_does_not_link_is_not_used(gl):
    """The fault "compile": glUseProgram of a program whose vertex shader
    does not compile is GL_INVALID_OPERATION in Mesa, and its draw runs the
    program in use: converted as Mesa draws it (the draw had been refused)."""
    r = gl(capture_path("shader-fault-compile"), "--check-depth")
    assert r.returncode == 0, f"--check-depth failed ({r.returncode}): {r.stdout}{r.stderr}"
    m = re.search(r"agreement: ([0-9.]+)% of (\d+) covered pixels in (\d+) frames", r.stdout)
    assert m and float(m.group(1)) >= 99.0 and int(m.group(2)) > 2000, r.stdout


# ---- Mesa's replay (glretrace under xvfb-run): its processes end with the
# run, and the check's failures name the capture.

def replay_processes(tmp):
    """{pid: command line} of the processes whose command line or
    environment names `tmp`, the TMPDIR the test gives the converter (Xvfb's
    -auth file lies in it, glretrace's TMPDIR is in it); a zombie has
    neither."""
    found = {}
    for entry in os.listdir("/proc"):
        if not entry.isdigit():
            continue
        try:
            with open(f"/proc/{entry}/cmdline", "rb") as f:
                cmd = f.read()
            with open(f"/proc/{entry}/environ", "rb") as f:
                env = f.read()
        except OSError:
            continue
        if tmp.encode() in cmd or tmp.encode() in env:
            found[int(entry)] = cmd.replace(b"\0", b" ").decode("utf-8", "replace").strip()
    return found


@pytest.mark.parametrize("replay, sig", [("read-back", signal.SIGTERM), ("check", signal.SIGHUP)])
def test_a_signal_while_mesa_replays_leaves_no_x_server(gl, replay, sig):
    """A signal while Mesa's replay runs under xvfb-run, as soon as its Xvfb
    exists: the texture read-back replay of a conversion and
    --check-depth's glretrace -D (round 17's R17-4: Xvfb had been left
    running, its parent 1, xvfb-run killed alone or its folder removed
    before it ended its server). The run ends as any interrupted run (exit
    130, one line), and no process of the run is left: not Xvfb, not
    glretrace (the replay's session ends with the converter, however it
    ends: allowed 3 s); Xvfb ended by SIGTERM, not SIGKILL, leaves no lock
    file holding its display number."""
    if not shutil.which("xvfb-run"):
        pytest.skip("xvfb-run is not installed (scripts/setup.sh --gl installs it)")
    cap, args, folder = {"read-back": (capture_path("shader-fault-rendered"), ("-o", gl.path("x.rbt")),
                                       "rbcd-gl2rbt-textures."),
                         "check": (capture_path("shaders"), ("--check-depth",), "rbcd-gl2rbt-check.")}[replay]
    gl.env.pop("DISPLAY", None)   # the replay under xvfb-run
    p = subprocess.Popen(["/usr/bin/python3", GL2RBT, cap] + list(args), env=gl.env, stdin=subprocess.DEVNULL,
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        deadline = time.monotonic() + 60
        while True:
            xvfb = [(pid, c) for pid, c in replay_processes(gl.tmp).items() if c.startswith("Xvfb ") and folder in c]
            if xvfb:
                break
            assert p.poll() is None and time.monotonic() < deadline, "the replay's Xvfb never started"
            time.sleep(0.005)
        p.send_signal(sig)
        out, err = p.communicate(timeout=60)
    finally:
        if p.poll() is None:
            p.kill()
            p.communicate()
    deadline = time.monotonic() + 3
    while replay_processes(gl.tmp) and time.monotonic() < deadline:
        time.sleep(0.02)
    left = replay_processes(gl.tmp)
    for pid in left:   # (the test's own clean-up, failing: SIGTERM, on which Xvfb removes its lock file)
        try:
            os.kill(pid, signal.SIGTERM)
        except ProcessLookupError:
            pass
    assert not left, f"left running: {left}"
    pid, display = xvfb[0][0], re.match(r"Xvfb :(\d+) ", xvfb[0][1]).group(1)
    try:
        with open(f"/tmp/.X{display}-lock") as f:
            holder = f.read().strip()
    except OSError:
        holder = None
    assert holder != str(pid), f"Xvfb :{display} was killed outright: its lock file is left"
    assert p.returncode == 130 and err.strip().splitlines() == [f"rbcd-gl2rbt: {cap}: interrupted"], \
        (p.returncode, err)
    assert not os.listdir(gl.tmp), os.listdir(gl.tmp)


def test_the_check_s_failures_name_the_capture(gl, tmp_path):
    """Mesa's replay dumping no depth buffer (a glretrace that says why and
    exits): the check fails in one line naming the capture and the call
    (round 17: it named neither), exit 1, nothing left."""
    bin_dir = tmp_path / "bin"
    bin_dir.mkdir()
    for tool in os.listdir("/usr/bin"):   # every tool but glretrace (a PATH of /usr/bin's tools)
        if tool != "glretrace":
            (bin_dir / tool).symlink_to(os.path.join("/usr/bin", tool))
    (bin_dir / "glretrace").write_text("#!/bin/sh\necho 'glretrace: no state here' >&2\nexit 1\n")
    (bin_dir / "glretrace").chmod(0o755)
    gl.env["PATH"] = str(bin_dir)
    cap = capture_path("shaders")
    r = gl(cap, "--check-depth")
    lines = r.stderr.strip().splitlines()
    assert r.returncode == 1 and len(lines) == 1 and \
        re.fullmatch(rf"rbcd-gl2rbt: {re.escape(cap)}: call \d+: Mesa's replay \(glretrace -D \d+\) dumped no depth "
                     r"buffer \(glretrace: no state here\)", lines[0]), lines
    assert not [f for f in os.listdir(gl.tmp) if f.startswith(("rbcd-gl2rbt", "."))], os.listdir(gl.tmp)


# A GL 4.5 core program, 64 x 48, one quad a frame at depth 0.625 (window
# rows 12 to 35, columns 16 to 47): frames 0 and 2 read its positions as
# floats, frame 1 as GL_FIXED through glVertexAttribPointer, frame 3 as
# GL_FIXED through glVertexAttribFormat and glBindVertexBuffer.
FIXED_PROGRAM = r"""
#define GL_GLEXT_PROTOTYPES 1
#include <GL/gl.h>
#include <GL/glext.h>
#include <GL/glx.h>
#include <X11/Xlib.h>
#include <string.h>
typedef GLXContext (*CreateContext)(Display *, GLXFBConfig, GLXContext, Bool, const int *);
static GLuint shader(GLenum kind, const char *src) {
    GLuint s = glCreateShader(kind);
    glShaderSource(s, 1, &src, NULL);
    glCompileShader(s);
    return s;
}
int main(void) {
    Display *dpy = XOpenDisplay(NULL);
    int a[] = {GLX_DRAWABLE_TYPE, GLX_WINDOW_BIT, GLX_RENDER_TYPE, GLX_RGBA_BIT, GLX_DOUBLEBUFFER, True,
               GLX_RED_SIZE, 8, GLX_GREEN_SIZE, 8, GLX_BLUE_SIZE, 8, GLX_DEPTH_SIZE, 24, 0};
    int n = 0;
    GLXFBConfig *c = dpy ? glXChooseFBConfig(dpy, DefaultScreen(dpy), a, &n) : NULL;
    if (!n) return 3;
    XVisualInfo *vi = glXGetVisualFromFBConfig(dpy, c[0]);
    XSetWindowAttributes swa;
    memset(&swa, 0, sizeof swa);
    swa.colormap = XCreateColormap(dpy, RootWindow(dpy, vi->screen), vi->visual, AllocNone);
    Window win = XCreateWindow(dpy, RootWindow(dpy, vi->screen), 0, 0, 64, 48, 0, vi->depth, InputOutput,
                               vi->visual, CWColormap, &swa);
    XMapWindow(dpy, win);
    XSync(dpy, False);
    CreateContext create = (CreateContext)glXGetProcAddress((const GLubyte *)"glXCreateContextAttribsARB");
    int attrs[] = {GLX_CONTEXT_MAJOR_VERSION_ARB, 4, GLX_CONTEXT_MINOR_VERSION_ARB, 5,
                   GLX_CONTEXT_PROFILE_MASK_ARB, GLX_CONTEXT_CORE_PROFILE_BIT_ARB, 0};
    GLXContext ctx = create ? create(dpy, c[0], NULL, True, attrs) : NULL;
    if (!ctx) return 3;
    glXMakeCurrent(dpy, win, ctx);
    GLuint p = glCreateProgram();
    glAttachShader(p, shader(GL_VERTEX_SHADER, "#version 330 core\nlayout(location = 0) in vec2 pos;\n"
                             "void main() { gl_Position = vec4(pos * 0.5, 0.25, 1.0); }\n"));
    glAttachShader(p, shader(GL_FRAGMENT_SHADER, "#version 330 core\nout vec4 c;\nvoid main() { c = vec4(1.0); }\n"));
    glLinkProgram(p);
    glUseProgram(p);
    GLfloat floats[8] = {-1, -1, 1, -1, -1, 1, 1, 1};
    GLint fixed[8] = {-65536, -65536, 65536, -65536, -65536, 65536, 65536, 65536};
    GLuint vao, vbo[2];
    glGenVertexArrays(1, &vao);
    glBindVertexArray(vao);
    glGenBuffers(2, vbo);
    glBindBuffer(GL_ARRAY_BUFFER, vbo[0]);
    glBufferData(GL_ARRAY_BUFFER, sizeof floats, floats, GL_STATIC_DRAW);
    glBindBuffer(GL_ARRAY_BUFFER, vbo[1]);
    glBufferData(GL_ARRAY_BUFFER, sizeof fixed, fixed, GL_STATIC_DRAW);
    glEnableVertexAttribArray(0);
    glEnable(GL_DEPTH_TEST);
    for (int f = 0; f < 4; f++) {
        glViewport(0, 0, 64, 48);
        glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
        if (f == 1) {
            glBindBuffer(GL_ARRAY_BUFFER, vbo[1]);
            glVertexAttribPointer(0, 2, GL_FIXED, GL_FALSE, 0, 0);
        } else if (f == 3) {
            glVertexAttribFormat(0, 2, GL_FIXED, GL_FALSE, 0);
            glBindVertexBuffer(0, vbo[1], 0, 8);
            glVertexAttribBinding(0, 0);
        } else {
            glBindBuffer(GL_ARRAY_BUFFER, vbo[0]);
            glVertexAttribPointer(0, 2, GL_FLOAT, GL_FALSE, 0, 0);
        }
        glDrawArrays(GL_TRIANGLE_STRIP, 0, 4);
        glXSwapBuffers(dpy, win);
    }
    glFinish();
    return glGetError() == GL_NO_ERROR ? 0 : 4;
}
"""


def test_the_check_leaves_out_frames_with_a_fixed_point_attribute(gl, tmp_path):
    """A desktop GL capture whose draws read a GL_FIXED vertex attribute
    (FIXED_PROGRAM, compiled and captured here): glretrace's state dump
    asserts on it (round 17's R17-5: the check failed after replaying,
    "dumped no depth buffer (Aborted)", naming neither the capture nor the
    call). The frames whose last depth-tested draw has it bound are left
    out, said so naming the call, and the others are checked; with only
    such frames selected the check refuses before replaying, in one line
    naming the capture and the call that made the attribute GL_FIXED."""
    missing = [t for t in ("cc", "xvfb-run", "apitrace", "glretrace") if not shutil.which(t)]
    if missing:
        pytest.skip(f"{', '.join(missing)} not installed (scripts/setup.sh --gl installs them)")
    (tmp_path / "fixed.c").write_text(FIXED_PROGRAM)
    exe, cap = tmp_path / "fixed", str(tmp_path / "fixed.trace")
    r = run(["cc", "-o", str(exe), str(tmp_path / "fixed.c"), "-lGL", "-lX11"])
    if r.returncode != 0:
        pytest.skip(f"the GL and X11 headers are missing (scripts/setup.sh --gl installs them): {r.stderr[-300:]}")
    r = run(["xvfb-run", "-a", "-s", "-screen 0 640x480x24", "apitrace", "trace", "-o", cap, str(exe)], timeout=120)
    assert r.returncode == 0 and os.path.exists(cap), f"capturing failed ({r.returncode}): {r.stderr[-400:]}"
    r = gl(cap, "--check-depth")
    assert r.returncode == 0, f"--check-depth failed ({r.returncode}): {r.stdout}{r.stderr}"
    assert re.search(r"^2 frames not checked: their last depth-tested draw has a GL_FIXED vertex attribute bound, "
                     r".*\(the first, frame 1: call \d+: glVertexAttribPointer\)$", r.stdout, re.M), r.stdout
    assert re.search(r"^frame 2 \(call \d+\): 100\.00% of 768 covered pixels agree", r.stdout, re.M), r.stdout
    assert "frame 1 (" not in r.stdout and "frame 3 (" not in r.stdout, r.stdout
    r = gl(cap, "--check-depth", "--frames", "3:3")
    lines = r.stderr.strip().splitlines()
    assert r.returncode == 2 and len(lines) == 1 and re.match(
        rf"rbcd-gl2rbt: {re.escape(cap)}: call \d+: glVertexAttribFormat: a GL_FIXED vertex attribute", lines[0]), \
        lines
    assert "frame 3 (" not in r.stdout, r.stdout
    assert not [f for f in os.listdir(gl.tmp) if f.startswith(("rbcd-gl2rbt", "."))], os.listdir(gl.tmp)


# ---- OpenGL ES 2.0 (testbench/gl/gles_boxes.c, through EGL): a "#version 100"
# shader, attributes and indices from client memory, a box from a buffer
# object. Boxes 1 and 2 as in gl_shaders, box 3 [60,70]x[8,18]x[-10,-5] in
# frame 0 and 30 to the right in frame 1, the floor as other work: 400 + 400 +
# 100 front fragments and as many back ones a frame, 1,600 other.

def gles_capture():
    p = os.path.join(os.path.dirname(capture_path("shaders")), "gles.trace")
    if not os.path.exists(p):
        pytest.skip("no OpenGL ES capture (gles_boxes needs the EGL and GLES headers: scripts/setup.sh --gl)")
    return p


def test_gles_convert(gl):
    cap = gles_capture()
    out, summary = gl.path("gles.rbt"), gl.path("s.jsonl")
    r = gl(cap, "-o", out, "--summary", summary)
    assert r.returncode == 0, r.stderr
    with open(summary) as f:
        frames = [json.loads(line) for line in f]
    assert [(s["fragments"], s["culled"], s["other"], s["objects"]) for s in frames] == \
        [(1800, 900, 1600, [1, 2, 3])] * 2, f"per-frame figures {frames}"
    trace, _ = read_trace(out)
    assert {o for _, o, _, _ in trace[0][(65, 85)]} == {3} and (65, 85) not in trace[1], "box 3 in frame 0"
    assert {o for _, o, _, _ in trace[1][(95, 85)]} == {3}, "box 3 moved by its uniform in frame 1"
    want = sorted([(round(0.55 * DEPTH_MAX), 1, "F", False), (round(0.60 * DEPTH_MAX), 1, "B", True)])
    assert sorted(trace[0][(10, 80)]) == want, "box 1's depths from client-memory vertices and indices"
    col = gl.path("c.txt")
    r = run([program("rbcd-sim"), "--trace", out, "--collisions", col, "-q"])
    assert r.returncode == 0, r.stderr
    with open(col) as f:
        hits = [tuple(line.split()[3:5]) for line in f if line.startswith("hit")]
    assert len(hits) == 2 * 8 * 12 and set(hits) == {("1", "2")}, f"{len(hits)} hits: {set(hits)}"


def test_gles_reduced_and_check(gl):
    cap = gles_capture()
    red = gl.path("gles.calls.xz")
    a = gl(cap, "-o", gl.path("a.rbt"), "--reduced-out", red)
    b = gl(red, "-o", gl.path("b.rbt"))
    assert a.returncode == 0 and b.returncode == 0, a.stderr + b.stderr
    with open(gl.path("a.rbt"), "rb") as f1, open(gl.path("b.rbt"), "rb") as f2:
        assert f1.read() == f2.read(), "the reduced ES capture converts differently"
    # Mesa's ES depth buffer, read back through gl/es_depth_readback.c
    # preloaded into glretrace: frame 1 (the first frame is checked only
    # alone) covers the floor's 40 x 40 pixels and the boxes' 400 + 400 + 100
    # beside and in front of it.
    r = gl(cap, "--check-depth")
    assert r.returncode == 0, f"--check-depth failed ({r.returncode}): {r.stdout}{r.stderr}"
    m = re.search(r"^agreement: ([0-9.]+)% of (\d+) covered pixels in 1 frames", r.stdout, re.M)
    assert m and float(m.group(1)) >= 99.0 and int(m.group(2)) >= 1600 + 400, r.stdout


def test_gles_textures_of_every_kind_read_back(gl):
    """gles_boxes' "layers" draw (frame 1, object 9): a "#version 320 es"
    vertex shader moves the cube's first triangle by what it reads from
    three textures framebuffer objects cleared, face +X of a cube map,
    slice 1 of a 3D texture and layer 1 of a DEPTH_COMPONENT24 2D array:
    each read back from Mesa's replay a layer or face at a time (OpenGL ES
    has no glGetTexImage; depth through NV_read_depth), where they had been
    refused; the triangle lands where the desktop faults' does, the check
    agrees (its state dump no longer aborts on the array left bound), and
    the reduced capture, which carries the six faces, converts to the same
    bytes (its faces had replaced one another)."""
    assert_moved_triangle(checked_and_reduced(gl, capture_path("gles-layers"), 3700))


def test_gles_check_without_readback(gl, tmp_path):
    """Without the readback library beside rbcd-gl-raster (built only with
    the OpenGL ES headers) the ES check says what is missing, in one line,
    before converting; a desktop capture's check does not need it."""
    cap = gles_capture()
    lone = tmp_path / "bin"
    lone.mkdir()
    raster = lone / "rbcd-gl-raster"
    shutil.copy(program("rbcd-gl-raster"), raster)
    gl.env["RBCD_GL_RASTER"] = str(raster)
    r = gl(cap, "--check-depth")
    lines = r.stderr.strip().splitlines()
    assert r.returncode == 1 and len(lines) == 1 and "rbcd-es-depth-readback.so" in lines[0] \
        and "libgles-dev" in lines[0], lines
    assert r.stdout == "", "the check printed figures before saying the library is missing"

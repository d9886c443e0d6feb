"""glmark2-es2 (Debian glmark2-es2-x11), an OpenGL ES 2.0 program we do not
modify, captured under Xvfb with apitrace and converted by scripts/rbcd-gl2rbt
with the shipped rules, workloads/games/glmark2-es2-select.toml
(docs/gl-capture.md, "OpenGL ES: glmark2-es2"). Skipped, saying why, without
glmark2-es2, apitrace or xvfb-run (scripts/setup.sh --gl installs them).

Three short scenes of its default list, each a capture of its own, 800 x 480:
  build:use-vbo=true  the horse, one glDrawArrays a frame, culling on
                      (glmark2 enables GL_CULL_FACE for every scene);
  pulsar:quads=5:texture=false:light=false
                      five flat quads, one glDrawArrays each a frame in one
                      order, culling off (the scene disables it);
  terrain             a grid of 393,216 vertices whose vertex shader
                      samples a height map an earlier pass of each frame
                      renders into a texture (read back from Mesa's replay).
What is asserted follows from those definitions, not from the converter's
figures: as many frames as nframes asks; the objects the rules name, every
frame; every fragment on the screen; a closed mesh under culling gives as
many back fragments as front ones, the back ones tagged c; a flat quad covers
a pixel once and, without culling, nothing is tagged c."""
import json
import os
import shutil
import subprocess

import pytest

from conftest import ROOT, program
from gl_captures import GL2RBT, read_trace, run

W, H = 800, 480
FRAMES = 8
RULES = os.path.join(ROOT, "workloads", "games", "glmark2-es2-select.toml")
SCENES = {"build": "build:use-vbo=true", "pulsar": "pulsar:quads=5:texture=false:light=false",
          "terrain": "terrain"}


def missing_tools():
    return [t for t in ("glmark2-es2", "apitrace", "xvfb-run") if not shutil.which(t)]


@pytest.fixture(scope="module")
def captures(tmp_path_factory):
    missing = missing_tools()
    if missing:
        pytest.skip(f"{', '.join(missing)} missing (scripts/setup.sh --gl installs glmark2-es2-x11, apitrace "
                    "and xvfb)")
    pytest.importorskip("OpenGL", reason="python3-opengl is missing (scripts/setup.sh --gl)")
    d = tmp_path_factory.mktemp("glmark2")
    out = {}
    for name, bench in SCENES.items():
        path = str(d / f"{name}.trace")
        r = run(["xvfb-run", "-a", "-s", "-screen 0 1280x1024x24", "apitrace", "trace", "--api", "egl", "-o", path,
                 "glmark2-es2", "-s", f"{W}x{H}", "-b", f"{bench}:nframes={FRAMES}"], timeout=120)
        assert r.returncode == 0 and os.path.exists(path), \
            f"capturing {bench} failed ({r.returncode}): {r.stderr.strip()[-400:]}"
        out[name] = path
    return d, out


def gl2rbt(d, *args):
    env = dict(os.environ, RBCD_GL_RASTER=program("rbcd-gl-raster"), TMPDIR=str(d))
    return subprocess.run(["/usr/bin/python3", GL2RBT] + [str(a) for a in args], stdout=subprocess.PIPE,
                          stderr=subprocess.PIPE, text=True, env=env, timeout=300)


def convert(captures, name):
    d, traces = captures
    out, summary = d / f"{name}.rbt", d / f"{name}.jsonl"
    r = gl2rbt(d, traces[name], "-o", out, "--select", RULES, "--summary", summary)
    assert r.returncode == 0, f"{name}: {r.stderr.strip()}"
    with open(summary) as f:
        frames = [json.loads(line) for line in f]
    trace, _ = read_trace(str(out))
    return frames, trace


def listed(captures, name, frame):
    """--list-draws FRAME with the rules: (object, rule) per draw."""
    d, traces = captures
    r = gl2rbt(d, traces[name], "--list-draws", frame, "--select", RULES)
    assert r.returncode == 0, r.stderr
    rows = [line.split() for line in r.stdout.splitlines()[2:] if line.strip()]
    # index, call, function, vertices, texture, image, program, data,
    # projection, own-mv, depth, func, box (4 numbers), object, rule (words)
    return [(row[16], " ".join(row[17:])) for row in rows]


def on_screen(trace):
    return all(0 <= x < W and 0 <= y < H for f in trace.values() for (x, y) in f)


def test_build_the_horse_is_object_1(captures):
    frames, trace = convert(captures, "build")
    assert len(frames) == FRAMES and sorted(trace) == list(range(FRAMES)), \
        f"{len(frames)} frames for nframes={FRAMES}"
    for s in frames:
        assert s["draws"] == 1 and s["objects"] == [1] and s["other"] == 0, f"frame {s['frame']}: {s}"
    assert on_screen(trace), "a fragment off the 800 x 480 screen"
    for f, pixels in trace.items():
        frags = [x for v in pixels.values() for x in v]
        front = [c for _, _, facing, c in frags if facing == "F"]
        back = [c for _, _, facing, c in frags if facing == "B"]
        assert {o for _, o, _, _ in frags} == {1}
        assert front and not any(front) and all(back), f"frame {f}: back faces are the culled ones, tagged c"
        # A closed mesh: each pixel's ray leaves it as often as it enters
        # (the horse's few open edges leave a fraction of a percent).
        assert abs(len(front) - len(back)) <= 0.01 * len(front), f"frame {f}: {len(front)} front, {len(back)} back"
    assert listed(captures, "build", FRAMES // 2) == [("1", "the scene's model")]


def test_pulsar_five_quads_keep_their_ids(captures):
    frames, trace = convert(captures, "pulsar")
    assert len(frames) == FRAMES and sorted(trace) == list(range(FRAMES))
    for s in frames:
        assert s["draws"] == 5 and s["objects"] == [1, 2, 3, 4, 5] and s["other"] == 0, f"frame {s['frame']}: {s}"
        assert s["culled"] == 0 and s["fragments"] > 0, f"frame {s['frame']}: culling is off, nothing tagged c"
    assert on_screen(trace), "a fragment off the 800 x 480 screen"
    for f, pixels in trace.items():
        for xy, v in pixels.items():
            ids = [o for _, o, _, _ in v]
            assert len(ids) == len(set(ids)), f"frame {f} {xy}: a flat quad covers a pixel twice: {ids}"
            assert not any(c for _, _, _, c in v)
    for frame in (1, FRAMES - 1):
        assert listed(captures, "pulsar", frame) == [(str(i), f"pulsar: quad {i}") for i in range(1, 6)], \
            f"frame {frame}: the quads by their order in the frame"


def test_terrain_reads_the_height_map_each_frame_renders(captures):
    """The terrain's vertex shader reads a texture the GPU renders each
    frame (it had been refused): converted, every frame; the reduced
    capture carries the images read back, and converting it (no replay)
    gives the same bytes. (That the read-back image is the one Mesa
    samples is the gl_shaders "rendered" fault's test: exact pixels.)"""
    d, traces = captures
    out, red, again = d / "terrain.rbt", d / "terrain.xz", d / "terrain-again.rbt"
    r = gl2rbt(d, traces["terrain"], "-o", out, "--reduced-out", red)
    assert r.returncode == 0, r.stderr
    r = gl2rbt(d, red, "-o", again)
    assert r.returncode == 0, r.stderr
    assert out.read_bytes() == again.read_bytes()
    trace, _ = read_trace(str(out))
    assert sorted(trace) == list(range(FRAMES)) and on_screen(trace)
    assert os.path.getsize(red) > 20_000, "the reduced capture carries no height map"

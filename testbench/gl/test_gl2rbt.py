#!/usr/bin/python3
"""scripts/rbcd-gl2rbt on captures of testbench/gl/gl_boxes.c (docs/gl-capture.md).

    test_gl2rbt.py CASE --dir D --program gl_boxes --raster rbcd-gl-raster --sim rbcd-sim

`capture` (the CTest fixture) captures gl_boxes under Xvfb with apitrace into
D: once as it is, and once per FAULT mode; the other cases read those
captures. Exit 0 pass, 1 fail, 77 skipped (with the reason).

What gl_boxes draws, 128 x 96, glOrtho(0, 128, 0, 96, -100, 100) in frames 0
and 1 (window y up, screen rows down: row = 95 - y):
  frame 0: box 1 [8,28]x[8,28]x[-20,-10] (client arrays), box 2
           [20,40]x[16,36]x[-15,-5] (a buffer object), box 3 [60,70]x[8,18]
           (immediate mode, an EXT_debug_marker group); a 40 x 40 floor and an
           8 x 4 overlay that are not collisionable.
  frame 1: box 2 [20,30]^2 inside box 1 [8,48]^2; box 3 drawn twice, the
           second time as a GL_EQUAL pass.
  frame 2: glFrustum, a sphere (id 4) overlapping box 1, box 2 apart.
Face-on boxes under an orthographic projection give width x height front
fragments and as many back ones (tagged c: culling is on); side faces are
edge-on and cover nothing.
"""
import argparse
import gzip
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
GL2RBT = os.path.join(ROOT, "scripts", "rbcd-gl2rbt")
SKIP = 77
FAULTS = ["nan", "index", "ortho", "list", "shader", "line", "underflow"]
DEPTH_MAX = (1 << 24) - 1


class Fail(Exception):
    pass


def check(cond, what):
    if not cond:
        raise Fail(what)


def run(cmd, **kw):
    return subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, **kw)


def read_trace(path):
    """{frame: {(x, y): [(depth, id, facing, culled)]}} and the tile records."""
    opener = gzip.open if path.endswith(".gz") else open
    frames, tiles, frame = {}, [], None
    with opener(path, "rt") as f:
        for line in f:
            t = line.split()
            if not t:
                continue
            if t[0] == "frame":
                frame = int(t[1])
                frames[frame] = {}
            elif t[0] == "tile":
                tiles.append((frame, line.strip()))
            elif t[0] == "f":
                x, y, depth, obj = (int(v) for v in t[1:5])
                frames[frame].setdefault((x, y), []).append((depth, obj, t[5], len(t) > 6 and t[6] == "c"))
    return frames, tiles


class Case:
    def __init__(self, a, tmp):
        self.a, self.tmp = a, tmp
        # The converter's temporaries go to this case's own directory, where
        # what is left behind can be seen.
        self.env = dict(os.environ, RBCD_GL_RASTER=a.raster, TMPDIR=tmp)

    def capture_path(self, name="boxes"):
        p = os.path.join(self.a.dir, name + ".trace")
        if not os.path.exists(p):
            raise SystemExit(SKIP)
        return p

    def gl2rbt(self, *args):
        return run(["/usr/bin/python3", GL2RBT] + list(args), env=self.env)

    def convert(self, *extra, name="boxes", out="boxes.rbt"):
        path = os.path.join(self.tmp, out)
        r = self.gl2rbt(self.capture_path(name), "-o", path, *extra)
        check(r.returncode == 0, f"conversion failed ({r.returncode}): {r.stderr.strip()}")
        return path, r

    # ------------------------------------------------------------ cases
    def capture(self):
        missing = [t for t in ("xvfb-run", "apitrace", "glretrace") if not shutil.which(t)]
        if missing:
            print(f"skipped: {', '.join(missing)} not installed (scripts/setup.sh --gl installs them)")
            raise SystemExit(SKIP)
        os.makedirs(self.a.dir, exist_ok=True)
        for name, extra in [("boxes", []), ("point", ["128", "96", "point"])] + \
                [(f"fault-{f}", ["128", "96", f]) for f in FAULTS]:
            out = os.path.join(self.a.dir, name + ".trace")
            if os.path.exists(out):
                os.unlink(out)
            r = run(["xvfb-run", "-a", "-s", "-screen 0 1024x768x24", "apitrace", "trace", "-o", out,
                     self.a.program] + extra, timeout=120)
            check(r.returncode == 0 and os.path.exists(out),
                  f"capturing {name} failed ({r.returncode}): {r.stderr.strip()[-400:]}")

    def convert_case(self):
        path, r = self.convert("--summary", os.path.join(self.tmp, "s.jsonl"))
        frames, tiles = read_trace(path)
        check(sorted(frames) == [0, 1, 2], f"frames {sorted(frames)}")
        with open(os.path.join(self.tmp, "s.jsonl")) as f:
            summary = [json.loads(l) for l in f]
        # Frame 0: (400 + 400 + 100) front fragments, as many back (c); 1600 + 32 other.
        s0, s1, s2 = summary
        check((s0["fragments"], s0["culled"], s0["other"], s0["objects"]) == (1800, 900, 1632, [1, 2, 3]),
              f"frame 0 figures {s0}")
        # Frame 1: (1600 + 100 + 100) x 2; the GL_EQUAL pass of box 3 is other work (its 100 front fragments).
        check((s1["fragments"], s1["culled"], s1["other"], s1["objects"]) == (3600, 1800, 1732, [1, 2, 3]),
              f"frame 1 figures {s1}")
        # Frame 2: closed objects: every covered pixel has a front and a back fragment.
        check(s2["objects"] == [1, 2, 4] and s2["fragments"] == 2 * s2["culled"] and s2["other"] == 32,
              f"frame 2 figures {s2}")
        for s, f in zip(summary, sorted(frames)):
            check(sum(len(v) for v in frames[f].values()) == s["fragments"], f"frame {f}: summary and trace differ")
            check(all(c == (fc == "B") for v in frames[f].values() for _, _, fc, c in v),
                  f"frame {f}: a back face not tagged c, or a front face tagged")
        # Pixel (10, 80) (window y 15) lies in box 1 only: its faces at eye z -10 and -20,
        # window depth 0.5 + 0.5 * 0.01 * |z| of 2^24 - 1.
        got = sorted(frames[0][(10, 80)])
        want = sorted([(round(0.55 * DEPTH_MAX), 1, "F", False), (round(0.60 * DEPTH_MAX), 1, "B", True)])
        check(got == want, f"pixel (10, 80) of frame 0: {got}, expected {want}")
        check((27, 80) in frames[0] and (28, 80) not in frames[0] and (8, 87) in frames[0] and (8, 88) not in frames[0],
              "box 1's edges are off by a pixel")
        # Tiles say how many primitives they set up, and the rest of the GPU's work as o records.
        check(all("prims=" in t and "cprims=" in t for _, t in tiles), "a tile without prims= or cprims=")
        # Gzip output when the name ends in .gz: the same trace.
        gz, _ = self.convert(out="boxes.rbt.gz")
        with open(gz, "rb") as f:
            check(f.read(2) == b"\x1f\x8b", "a .gz output is not gzip")
        check(read_trace(gz)[0] == frames, "the .gz output differs from the plain one")
        check("collisionable objects" in r.stdout, f"no summary line: {r.stdout!r}")

    def pairs(self):
        path, _ = self.convert()
        col = os.path.join(self.tmp, "c.txt")
        r = run([self.a.sim, "--trace", path, "--collisions", col, "-q"])
        check(r.returncode == 0, f"rbcd-sim failed: {r.stderr.strip()}")
        hits, frame = {}, None
        with open(col) as f:
            for line in f:
                t = line.split()
                if t[0] == "frame":
                    frame = int(t[1])
                    hits[frame] = {}
                elif t[0] == "hit":
                    k = (int(t[3]), int(t[4]))
                    hits[frame][k] = hits[frame].get(k, 0) + 1
        # Overlap, one inside another, and a sphere against a box; box 3 and
        # frame 2's box 2 are apart from everything.
        check(hits[0] == {(1, 2): 8 * 12}, f"frame 0 pairs {hits[0]}")
        check(hits[1] == {(1, 2): 10 * 10}, f"frame 1 pairs {hits[1]}")
        check(set(hits[2]) == {(1, 4)}, f"frame 2 pairs {hits[2]}")

    def mesa(self):
        r = self.gl2rbt(self.capture_path(), "--check-depth")
        check(r.returncode == 0, f"--check-depth failed ({r.returncode}): {r.stdout}{r.stderr}")
        m = re.search(r"agreement: ([0-9.]+)% of (\d+) covered pixels in (\d+) frames", r.stdout)
        check(m and float(m.group(1)) >= 99.0 and int(m.group(2)) > 1000 and int(m.group(3)) == 2,
              f"agreement below 99% or too little checked: {r.stdout}")

    def refusals(self):
        expect = {"nan": "non-finite", "index": "reach past", "ortho": "empty volume", "list": "glNewList",
                  "shader": "program", "line": "GL_FILL", "underflow": "underflows"}
        for fault, words in expect.items():
            out = os.path.join(self.tmp, f"{fault}.rbt")
            geo = os.path.join(self.tmp, f"{fault}.geo")
            r = self.gl2rbt(self.capture_path(f"fault-{fault}"), "-o", out, "--geometry", geo)
            lines = r.stderr.strip().splitlines()
            check(r.returncode == 2, f"{fault}: exit {r.returncode}: {r.stderr.strip()}")
            check(len(lines) == 1 and re.search(r": call \d+: ", lines[0]) and words in lines[0],
                  f"{fault}: message {lines}")
            check(not os.path.exists(out) and not os.path.exists(geo), f"{fault}: an output was left")
            check(not [f for f in os.listdir(self.tmp) if f.startswith(".")], f"{fault}: a temporary was left")
        # A capture cut short, and one with bytes overwritten.
        src = self.capture_path()
        with open(src, "rb") as f:
            data = f.read()
        for name, body in (("cut", data[: len(data) // 3]),
                           ("corrupt", data[:20000] + b"\xff" * 16 + data[20016:])):
            p = os.path.join(self.tmp, name + ".trace")
            with open(p, "wb") as f:
                f.write(body)
            out = os.path.join(self.tmp, name + ".rbt")
            r = self.gl2rbt(p, "-o", out)
            lines = r.stderr.strip().splitlines()
            check(r.returncode == 2 and len(lines) == 1 and "call" in lines[0], f"{name}: {r.returncode} {lines}")
            check(not os.path.exists(out), f"{name}: an output was left")

    def select(self):
        """Selection rules for untagged draws: the floor of frame 0 (call
        range, vertex count) becomes object 9; a bad rules file is one line
        naming the key; --list-draws says what each draw became and why."""
        cap = self.capture_path()
        listing = self.gl2rbt(cap, "--list-draws", "0")
        check(listing.returncode == 0, f"--list-draws failed: {listing.stderr}")
        floor = [l for l in listing.stdout.splitlines() if "glDrawArrays" in l]
        check(len(floor) == 1 and "untagged" in floor[0], f"the floor's listing: {floor}")
        call = int(floor[0].split()[1])
        rules = os.path.join(self.tmp, "rules.toml")
        with open(rules, "w") as f:
            f.write(f'[[exclude]]\nname = "2D"\nprojection = "perspective"\n\n'
                    f'[[object]]\nname = "floor"\nid = 9\ncalls = [{call}, {call}]\nvertex_count = [4, 4]\n')
        path, _ = self.convert("--select", rules, "--summary", os.path.join(self.tmp, "s.jsonl"))
        with open(os.path.join(self.tmp, "s.jsonl")) as f:
            s0 = json.loads(f.readline())
        check(s0["objects"] == [1, 2, 3, 9] and s0["fragments"] == 1800 + 1600 and s0["other"] == 32,
              f"the floor did not become object 9: {s0}")
        frames, _ = read_trace(path)
        check(frames[0][(100, 50)] == [(round(0.75 * DEPTH_MAX), 9, "F", False)],
              f"the floor's fragment at (100, 50): {frames[0].get((100, 50))}")
        listing = self.gl2rbt(cap, "--list-draws", "0", "--select", rules, "--image", os.path.join(self.tmp, "f0.png"))
        floor = [l for l in listing.stdout.splitlines() if "glDrawArrays" in l]
        check(floor and floor[0].split()[-2:] == ["9", "floor"], f"the listing does not say floor: {floor}")
        with open(os.path.join(self.tmp, "f0.png"), "rb") as f:
            check(f.read(8) == b"\x89PNG\r\n\x1a\n", "--image wrote no PNG")
        for body, key in (('[[object]]\nid = 1\nvertex_count = [5, 2]\n', "vertex_count"),
                          ('[[object]]\nid = 1\nbogus = 1\n', "bogus"),
                          ('[[object]]\nname = "x"\n', "needs id"),
                          ('[[object]\n', "rules.toml")):
            with open(rules, "w") as f:
                f.write(body)
            out = os.path.join(self.tmp, "sel.rbt")
            r = self.gl2rbt(cap, "-o", out, "--select", rules)
            lines = r.stderr.strip().splitlines()
            check(r.returncode == 2 and len(lines) == 1 and key in lines[0] and "rules.toml" in lines[0],
                  f"rules {body!r}: {r.returncode} {lines}")
            check(not os.path.exists(out), "an output was left after a bad rules file")

    def geometry(self):
        """--geometry through rbcd-cpucd: the ground truth has each frame's
        pairs (overlap, one inside another, sphere and box), on screen."""
        if not self.a.cpucd:
            print("skipped: rbcd-cpucd is not built (Bullet and FCL: scripts/setup.sh --eval)")
            raise SystemExit(SKIP)
        geo = os.path.join(self.tmp, "boxes.geo")
        self.convert("--geometry", geo)
        csv_path = os.path.join(self.tmp, "pairs.csv")
        r = run([self.a.cpucd, "--geometry", geo, "--pairs", csv_path, "-q"])
        check(r.returncode == 0, f"rbcd-cpucd failed: {r.stderr.strip()}")
        with open(csv_path) as f:
            rows = [l.strip().split(",") for l in f][1:]
        exact = {(int(r[0]), int(r[1]), int(r[2])): (r[5], r[6], r[7]) for r in rows if r[5] == "1"}
        check(exact == {(0, 1, 2): ("1", "0", "1"), (1, 1, 2): ("1", "1", "1"), (2, 1, 4): ("1", "0", "1")},
              f"ground truth pairs (frame, a, b): (exact, contained, on_screen) = {exact}")
        # An object scaled to a point (object 9 in frame 1 of the "point"
        # capture) has no surface: no fragment, no mesh record, and the file
        # stays readable (rbcd-cpucd refuses a mesh of fewer than 3 vertices).
        geo9 = os.path.join(self.tmp, "point.geo")
        path, _ = self.convert("--geometry", geo9, name="point", out="point.rbt")
        with open(geo9) as f:
            meshes = [l.split()[1] for l in f if l.startswith("mesh ")]
        check("9" not in meshes and {"1", "2", "3"} <= set(meshes), f"mesh ids of the point capture: {sorted(set(meshes))}")
        frames9, _ = read_trace(path)
        check(all(obj != 9 for pixels in frames9.values() for frags in pixels.values() for _, obj, _, _ in frags),
              "object 9 has fragments")
        r = run([self.a.cpucd, "--geometry", geo9, "--pairs", os.path.join(self.tmp, "p9.csv"), "-q"])
        check(r.returncode == 0, f"rbcd-cpucd on the point capture's geometry: {r.stderr.strip()}")

    def frames(self):
        whole, _ = self.convert()
        part, _ = self.convert("--frames", "1:2", out="part.rbt")
        a, b = read_trace(whole)[0], read_trace(part)[0]
        check(sorted(b) == [0, 1] and b[0] == a[1] and b[1] == a[2], "--frames 1:2 is not frames 1 and 2, renumbered")
        last, _ = self.convert("--frames", "2:", out="last.rbt")
        check(read_trace(last)[0] == {0: a[2]}, "--frames 2: is not the last frame")

    def reduced(self):
        """--reduced-out: the reduced capture converts into the same trace and
        geometry as the capture (all frames and a range), is a fraction of its
        size, and a damaged one is refused in one line."""
        red = os.path.join(self.tmp, "boxes.calls.xz")
        self.convert("--reduced-out", red)
        for extra, tag in (([], "all"), (["--frames", "1:2"], "1:2")):
            a_path, _ = self.convert(*extra, "--geometry", os.path.join(self.tmp, f"c-{tag}.geo"), out=f"c-{tag}.rbt")
            r = self.gl2rbt(red, "-o", os.path.join(self.tmp, f"r-{tag}.rbt"),
                            "--geometry", os.path.join(self.tmp, f"r-{tag}.geo"), *extra)
            check(r.returncode == 0, f"the reduced capture does not convert: {r.stderr.strip()}")
            for ext in ("rbt", "geo"):
                with open(os.path.join(self.tmp, f"c-{tag}.{ext}"), "rb") as f1, \
                        open(os.path.join(self.tmp, f"r-{tag}.{ext}"), "rb") as f2:
                    check(f1.read() == f2.read(), f"frames {tag}: the reduced capture's .{ext} differs")
        size, full = os.path.getsize(red), os.path.getsize(self.capture_path())
        check(size < full / 2, f"the reduced capture is {size} bytes, the capture {full}")
        with open(red, "rb") as f:
            data = f.read()
        bad = os.path.join(self.tmp, "bad.calls.xz")
        out = os.path.join(self.tmp, "bad.rbt")
        for body, words in ((data[:len(data) // 2], "reduced capture"),
                            (data[:-1], "reduced capture"),
                            (data[:6] + b"\0" * 40, "does not decode")):
            with open(bad, "wb") as f:
                f.write(body)
            r = self.gl2rbt(bad, "-o", out)
            lines = r.stderr.strip().splitlines()
            check(r.returncode == 2 and len(lines) == 1 and words in lines[0] and "bad.calls.xz" in lines[0],
                  f"a damaged reduced capture: exit {r.returncode}, {lines}")
            check(not os.path.exists(out), "an output was left after a damaged reduced capture")
        r = self.gl2rbt(red, "--check-depth")
        check(r.returncode == 2 and "reduced capture" in r.stderr, f"--check-depth on a reduced capture: {r.stderr}")
        r = self.gl2rbt(red, "-o", out, "--reduced-out", os.path.join(self.tmp, "again.xz"))
        check(r.returncode == 2 and "already a reduced capture" in r.stderr, f"reducing twice: {r.stderr}")

    def cli(self):
        cap = self.capture_path()
        out = os.path.join(self.tmp, "x.rbt")
        cases = [
            ([cap, "-o", out, "--frames", "3:1"], "selects no frame"),
            ([cap, "-o", out, "--frames", "x"], "--frames"),
            ([cap, "-o", out, "--frames", "7:"], "has 3 frames"),
            ([cap, "-o", out, "--depth-bits", "0"], "--depth-bits"),
            ([cap, "-o", cap], "is the capture itself"),
            ([cap], "-o OUT is required"),
            ([self.tmp, "-o", out], "not a regular file"),
            ([os.path.join(self.tmp, "none.trace"), "-o", out], "cannot open"),
            ([cap, "-o", os.path.join(self.tmp, "no", "x.rbt")], "cannot create"),
            ([cap, "-o", out, "--select", os.path.join(self.tmp, "none.toml")], "cannot read"),
        ]
        for args, words in cases:
            r = self.gl2rbt(*args)
            lines = r.stderr.strip().splitlines()
            check(r.returncode == 2 and len(lines) == 1 and words in lines[0],
                  f"{args[1:]}: exit {r.returncode}, {lines}")
            check(not os.path.exists(out), f"{args[1:]}: an output was left")
        left = [d for d in os.listdir(self.tmp) if d.startswith("rbcd-gl2rbt")]
        check(not left, f"temporary directories left by the refusals: {left}")
        with open(cap, "rb") as f:
            before = f.read()
        self.gl2rbt(cap, "-o", cap)
        with open(cap, "rb") as f:
            check(f.read() == before, "the capture was touched")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("case")
    ap.add_argument("--dir", required=True)
    ap.add_argument("--program", required=True)
    ap.add_argument("--raster", required=True)
    ap.add_argument("--sim", required=True)
    ap.add_argument("--cpucd", default="")
    a = ap.parse_args()
    tmp = tempfile.mkdtemp(prefix="test_gl2rbt.")
    try:
        c = Case(a, tmp)
        name = {"convert": "convert_case"}.get(a.case, a.case)
        if a.case != "capture" and not os.path.exists(os.path.join(a.dir, "boxes.trace")):
            print("skipped: no captures (gl_capture was skipped: scripts/setup.sh --gl installs Xvfb and apitrace)")
            return SKIP
        getattr(c, name)()
        print(f"{a.case}: passed")
        return 0
    except Fail as e:
        print(f"FAIL {a.case}: {e}")
        return 1
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


if __name__ == "__main__":
    sys.exit(main())

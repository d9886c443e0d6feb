"""The captures the GL tests read (CTest fixture gl_captures): gl_boxes (GL
1.x) and gl_shaders (GL 3.3 core) under Xvfb with apitrace, once as they are
and once per FAULT mode."""
import os
import shutil

import pytest

from gl_captures import CAPTURES, FAULTS, SHADER_FAULTS, run


def test_capture():
    missing = [t for t in ("xvfb-run", "apitrace", "glretrace") if not shutil.which(t)]
    if missing:
        pytest.skip(f"{', '.join(missing)} not installed (scripts/setup.sh --gl installs them)")
    boxes, shaders = os.environ.get("RBCD_GL_BOXES"), os.environ.get("RBCD_GL_SHADERS")
    if not boxes or not shaders:
        pytest.skip("RBCD_GL_BOXES or RBCD_GL_SHADERS names no program (CTest sets them; the GL headers: "
                    "scripts/setup.sh --gl)")
    os.makedirs(CAPTURES, exist_ok=True)
    # "wide": a window of 4100 x 4100, past what --check-depth lets
    # glretrace grow to.
    for name, program, extra in [("boxes", boxes, []), ("point", boxes, ["128", "96", "point"]),
                                 ("readother", boxes, ["128", "96", "readother"]),
                                 ("glsl", boxes, ["128", "96", "glsl"]),
                                 ("wide", boxes, ["4100", "4100"])] + \
            [(f"fault-{f}", boxes, ["128", "96", f]) for f in FAULTS] + [("shaders", shaders, [])] + \
            [(f"shader-fault-{f}", shaders, ["128", "96", f]) for f in SHADER_FAULTS]:
        out = os.path.join(CAPTURES, name + ".trace")
        capture(name, ["-o", out, program] + extra)
    # The OpenGL ES program (through EGL): its tests skip without it.
    gles = os.environ.get("RBCD_GLES_BOXES")
    if gles:
        capture("gles", ["--api", "egl", "-o", os.path.join(CAPTURES, "gles.trace"), gles])
        capture("gles-layers", ["--api", "egl", "-o", os.path.join(CAPTURES, "gles-layers.trace"), gles,
                                "128", "96", "layers"])


def capture(name, args):
    out = args[args.index("-o") + 1]
    if os.path.exists(out):
        os.unlink(out)
    r = run(["xvfb-run", "-a", "-s", "-screen 0 1024x768x24", "apitrace", "trace"] + args, timeout=120)
    assert r.returncode == 0 and os.path.exists(out), \
        f"capturing {name} failed ({r.returncode}): {r.stderr.strip()[-400:]}"

"""The captures the GL tests read (CTest fixture gl_captures): gl_boxes under
Xvfb with apitrace, once as it is and once per FAULT mode (gl_captures.py
says what it draws)."""
import os
import shutil

import pytest

from gl_captures import CAPTURES, FAULTS, run


def test_capture():
    missing = [t for t in ("xvfb-run", "apitrace", "glretrace") if not shutil.which(t)]
    if missing:
        pytest.skip(f"{', '.join(missing)} not installed (scripts/setup.sh --gl installs them)")
    program = os.environ.get("RBCD_GL_BOXES")
    if not program:
        pytest.skip("RBCD_GL_BOXES names no gl_boxes program (CTest sets it; the GL headers: scripts/setup.sh --gl)")
    os.makedirs(CAPTURES, exist_ok=True)
    for name, extra in [("boxes", []), ("point", ["128", "96", "point"])] + \
            [(f"fault-{f}", ["128", "96", f]) for f in FAULTS]:
        out = os.path.join(CAPTURES, name + ".trace")
        if os.path.exists(out):
            os.unlink(out)
        r = run(["xvfb-run", "-a", "-s", "-screen 0 1024x768x24", "apitrace", "trace", "-o", out, program] + extra,
                timeout=120)
        assert r.returncode == 0 and os.path.exists(out), \
            f"capturing {name} failed ({r.returncode}): {r.stderr.strip()[-400:]}"

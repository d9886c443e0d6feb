#!/usr/bin/python3
"""Figure 8's CPU model (scripts/cpu_model.py) on a worked example: its
constants' arithmetic, so that a changed constant is a deliberate change of
this test and of docs/results.md together."""
import math
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "scripts"))
import cpu_model  # noqa: E402

failures = []


def close(what, got, want):
    if not math.isclose(got, want, rel_tol=1e-12):
        failures.append(f"{what}: {got!r}, expected {want!r}")


# The constants as docs/results.md states them.
close("clock GHz", cpu_model.CLOCK_GHZ, 1.5)
close("CPI", cpu_model.CPI, 1.0)
# Exynos 5250: 4.0 W for two A15 cores at 1.7 GHz -> 2.0 W a core -> x 1.5 / 1.7 at 1.5 GHz.
close("active core W", cpu_model.ACTIVE_CORE_W, 2.0 * 1.5 / 1.7)
close("idle core W", cpu_model.IDLE_CORE_W, 0.109)
# 3 million instructions a frame: 3e6 x 1.0 / 1.5e9 = 2 ms; energy 2 ms x (1.764706 + 0.109) W = 3.747412 mJ.
close("seconds", cpu_model.seconds(3e6), 2e-3)
close("joules", cpu_model.joules(3e6), 2e-3 * (30.0 / 17.0 + 0.109))
close("nJ per instruction", cpu_model.nj_per_instruction(), (30.0 / 17.0 + 0.109) / 1.5)
# Speed-up against a GPU that spends 10 us more per frame with the unit: 2 ms / 10 us = 200.
close("speed-up", cpu_model.seconds(3e6) / 10e-6, 200.0)
if "1.874 W" not in cpu_model.describe():
    failures.append(f"describe(): {cpu_model.describe()}")
for f in failures:
    print("test_cpu_model.py:", f, file=sys.stderr)
if failures:
    sys.exit(1)
print("test_cpu_model.py: ok")

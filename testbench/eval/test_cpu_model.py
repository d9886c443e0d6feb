"""Figure 8's CPU model (python/rbcd/cpu_model.py) on a worked example: its
constants' arithmetic, so that a changed constant is a deliberate change of
this test and of docs/results.md together."""
import math

from rbcd import cpu_model


def close(got, want):
    return math.isclose(got, want, rel_tol=1e-12)


def test_cpu_model():
    # The constants as docs/results.md states them.
    assert close(cpu_model.CLOCK_GHZ, 1.5), f"clock GHz: {cpu_model.CLOCK_GHZ!r}, expected 1.5"
    assert close(cpu_model.CPI, 1.0), f"CPI: {cpu_model.CPI!r}, expected 1.0"
    # Exynos 5250: 4.0 W for two A15 cores at 1.7 GHz -> 2.0 W a core -> x 1.5 / 1.7 at 1.5 GHz.
    assert close(cpu_model.ACTIVE_CORE_W, 2.0 * 1.5 / 1.7), \
        f"active core W: {cpu_model.ACTIVE_CORE_W!r}, expected {2.0 * 1.5 / 1.7!r}"
    assert close(cpu_model.IDLE_CORE_W, 0.109), f"idle core W: {cpu_model.IDLE_CORE_W!r}, expected 0.109"
    # 3 million instructions a frame: 3e6 x 1.0 / 1.5e9 = 2 ms; energy 2 ms x (1.764706 + 0.109) W = 3.747412 mJ.
    assert close(cpu_model.seconds(3e6), 2e-3), f"seconds: {cpu_model.seconds(3e6)!r}, expected 2e-3"
    want = 2e-3 * (30.0 / 17.0 + 0.109)
    assert close(cpu_model.joules(3e6), want), f"joules: {cpu_model.joules(3e6)!r}, expected {want!r}"
    want = (30.0 / 17.0 + 0.109) / 1.5
    assert close(cpu_model.nj_per_instruction(), want), \
        f"nJ per instruction: {cpu_model.nj_per_instruction()!r}, expected {want!r}"
    # Speed-up against a GPU that spends 10 us more per frame with the unit: 2 ms / 10 us = 200.
    assert close(cpu_model.seconds(3e6) / 10e-6, 200.0), f"speed-up: {cpu_model.seconds(3e6) / 10e-6!r}, expected 200"
    assert "1.874 W" in cpu_model.describe(), f"describe(): {cpu_model.describe()}"

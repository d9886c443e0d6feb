"""The CPU of Figure 8, modelled from counted work (docs/results.md, "CPU model").

rbcd-cpucd --count-instructions counts the instructions the detection code
executes per frame (x86-64, under callgrind; docs/cpucd.md). This module turns
a count into the time and energy the paper's CPU would take: the paper's Table
2 CPU is two out-of-order cores at 1.5 GHz in 32 nm, simulated in MARSS (an
x86-64 simulator, so the instruction set counted here is the one it ran),
energy from McPAT. Every constant is here, each with where it comes from; a
count gives the same time and energy on any machine.
"""

# The paper's Table 2: 1.5 GHz.
CLOCK_GHZ = 1.5

# Cycles per instruction of one core on this code. Assumption, not a
# measurement: a 3-wide out-of-order mobile core (Cortex-A15 class, like the
# paper's) sustains about one instruction a cycle on the broad phase's tree
# walks (dependent loads) and GJK's chains of dependent floating-point
# operations, a third of its peak. The modelled time is proportional to it;
# the host's own CPI on the same code is in fig8.csv for comparison.
CPI = 1.0

# Power of the core that runs the detection (collision detection in Bullet is
# single-threaded). Exynos 5250 (two Cortex-A15 at 1.7 GHz, Samsung 32 nm):
# "just over 4 W" for the CPU running a multithreaded CoreMark on both cores
# (AnandTech, "ARM vs x86: The Real Showdown", 2013, page 13) -> 2.0 W a core,
# scaled to 1.5 GHz in proportion to the clock (voltage held: an upper bound
# on the dynamic part at the lower clock).
EXYNOS_CPU_W, EXYNOS_CORES, EXYNOS_GHZ = 4.0, 2, 1.7
ACTIVE_CORE_W = EXYNOS_CPU_W / EXYNOS_CORES * CLOCK_GHZ / EXYNOS_GHZ

# The other core idles, leaking. McPAT's stock dual Cortex-A9 configuration
# (ARM_A9_2GHz.xml, 40 nm, low-operating-power devices; McPAT 1.3's output):
# processor peak power 1.742 W, total leakage 0.109 W (two cores, their
# first-level directory and bus). An A15 core has about twice an A9's area,
# so one idle A15 at 32 nm is taken to leak what that dual A9 does.
IDLE_CORE_W = 0.109

POWER_W = ACTIVE_CORE_W + IDLE_CORE_W


def seconds(instructions):
    """Time on the paper's CPU for `instructions` executed on one core."""
    return instructions * CPI / (CLOCK_GHZ * 1e9)


def joules(instructions):
    """Energy of the two cores while one executes `instructions`."""
    return seconds(instructions) * POWER_W


def nj_per_instruction():
    return joules(1) * 1e9


def describe():
    """One line naming the model's constants, for the tables."""
    return (f"CPU model: {CLOCK_GHZ} GHz, CPI {CPI}, active core {ACTIVE_CORE_W:.3f} W + idle core "
            f"{IDLE_CORE_W} W = {POWER_W:.3f} W ({nj_per_instruction():.3f} nJ per instruction)")

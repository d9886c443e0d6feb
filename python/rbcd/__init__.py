"""rbcd: the Python tools of rbcd-tlm (docs/python.md).

    rbcd.cli          the project's rules for inputs, outputs and messages
    rbcd.startup      signals while a launcher loads its tool (before the tool's own handlers)
    rbcd.sweep        rbcd-sweep: design-space sweeps, local or on SLURM
    rbcd.plot         rbcd-plot: plots of sweep results and tile databases
    rbcd.evaluate     the paper's figures and tables (scripts/reproduce.sh)
    rbcd.cpu_model    Figure 8's CPU side: instructions to time and energy
    rbcd.game_suite   game-suite: check and expand the committed game captures
    rbcd.gl2rbt       rbcd-gl2rbt: captured OpenGL streams into the unit's input

Each tool's `main(argv=None)` returns its exit status; the commands in
scripts/ and the installed ones are launchers of these.
"""

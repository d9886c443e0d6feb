"""Signals while a program starts: its launcher's first lines (scripts/),
before Python loads the program's modules and its own handlers are in
place (rbcd.cli.main_wrapper, rbcd.gl2rbt.cli.main). SIGINT, SIGTERM and
SIGHUP are blocked before Python starts, by the launcher's interpreter line
(`env --block-signal`: a SIGINT while Python imports its own site module is
Python's fatal error, a traceback no line of the launcher can catch), and
again by the launcher's first statement (the builtin _signal, at once) when
it is run as `python3 LAUNCHER`; hold_signals takes one that came
meanwhile. Nothing exists yet
to remove, so a signal then ends the start-up in the program's one line,
"interrupted", exit 130, not in a traceback or a silent death. SIGINT or
SIGHUP ignored when the program started (a script's background job,
nohup) stays ignored."""
import os
import signal

HANDLED = (signal.SIGINT, signal.SIGTERM, signal.SIGHUP)


def kept(sig):
    """Whether the program takes `sig` (not one ignored from the start)."""
    return sig == signal.SIGTERM or signal.getsignal(sig) is not signal.SIG_IGN


def hold_signals(prog):
    """Start-up's handlers; a signal blocked before (across an exec) comes
    now."""
    def interrupted(signum, frame):
        os.write(2, f"{prog}: interrupted\n".encode())
        os._exit(130)
    for sig in HANDLED:
        if kept(sig):
            signal.signal(sig, interrupted)
    signal.pthread_sigmask(signal.SIG_UNBLOCK, HANDLED)


def ignore_signals():
    """The program's work has ended (done, failed or interrupted): a signal
    from here on changes nothing, and cannot end the process as Python
    finishes (its exit status is the work's; Python restores the default
    action of a signal it handled, not of one ignored)."""
    for sig in HANDLED:
        signal.signal(sig, signal.SIG_IGN)


def release_signals():
    """The program's own turn: SIGINT raises KeyboardInterrupt again
    (Python's default), the others as the program sets them."""
    if kept(signal.SIGINT):
        signal.signal(signal.SIGINT, signal.default_int_handler)

"""Mesa's replay of a capture, glretrace, as --check-depth and the read-back
textures run it: a library of ours preloaded into glretrace alone (not into
Xvfb), under xvfb-run when there is no DISPLAY."""
import os
import shutil

from .errors import ToolError, printable


def preload_library(name, what, headers, package):
    """One of gl/'s libraries preloaded into glretrace, beside rbcd-gl-raster
    as bin/../lib/rbcd/ (the build tree and an installed tree alike); `what`
    needs it, and it is built with `headers` (`package` installs them)."""
    from .raster import raster_program
    lib = os.path.normpath(os.path.join(os.path.dirname(raster_program()), "..", "lib", "rbcd", name))
    if not os.path.isfile(lib):
        raise ToolError(f"{what} needs {printable(lib)}, built with the {headers} headers (scripts/setup.sh --gl "
                        f"installs {package}; then build again)")
    return lib


def glretrace_command(args, what, preload=None, env=()):
    """The command that runs glretrace with `args` (`what` needs it), with
    `preload` before any LD_PRELOAD of the caller's and `env` (name=value)
    set for glretrace."""
    exe = shutil.which("glretrace")
    if not exe:
        raise ToolError(f"{what} needs glretrace (scripts/setup.sh --gl installs apitrace)")
    cmd = [exe] + list(args)
    if preload or env:
        preload = ":".join(p for p in (preload, os.environ.get("LD_PRELOAD")) if p)
        cmd = ["env"] + ([f"LD_PRELOAD={preload}"] if preload else []) + list(env) + cmd
    if not os.environ.get("DISPLAY"):
        xvfb = shutil.which("xvfb-run")
        if not xvfb:
            raise ToolError("no DISPLAY and no xvfb-run for glretrace (scripts/setup.sh --gl installs xvfb)")
        cmd = [xvfb, "-a", "-s", "-screen 0 1280x1024x24"] + cmd
    return cmd

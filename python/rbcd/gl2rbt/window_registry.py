"""The window systems' registries as the converter reads them: GLX's and
WGL's functions and enumerants (Khronos' glx.xml and wgl.xml, beside gl.xml
in Debian's khronos-api) and EGL's (its headers, Debian's libegl-dev: Debian
ships no egl.xml, and the headers are generated from it, one prototype and
one #define a line). Two uses:

- a reduced capture's record of a window-system call must name a function
  apitrace records and carry its parameters by apitrace's names
  (reduced.in_order), as a GL call's must (gl_registry);
- an enumerant of the window system (an attribute list's attributes and
  profile bits, eglBindAPI's API) is read by value, whether given by name
  as apitrace writes it or by value (value, attributes): a core context
  asked for with [0x2091, 3, 0x2092, 3, 0x9126, 1] is the core context
  apitrace's names ask for.

Reading all three takes about 20 ms, done at the first call that needs it
(no cache)."""
import re
import xml.etree.ElementTree as ET

from .errors import ToolError, printable

XML_REGISTRIES = ("/usr/share/khronos-api/glx.xml", "/usr/share/khronos-api/wgl.xml")
EGL_HEADERS = ("/usr/include/EGL/egl.h", "/usr/include/EGL/eglext.h")
PREFIXES = {"glX": "GLX", "egl": "EGL", "wgl": "WGL"}

# apitrace's parameter names where they differ from the registry's
# (apitrace 11.1's specs glxapi.py and wglapi.py; its eglapi.py names every
# parameter as the headers do).
APITRACE_NAMES = {
    "glXChooseFBConfig": ("dpy", "screen", "attribList", "nitems"),
    "glXCreateWindow": ("dpy", "config", "win", "attribList"), "glXDestroyWindow": ("dpy", "window"),
    "glXCreatePixmap": ("dpy", "config", "pixmap", "attribList"), "glXCreatePbuffer": ("dpy", "config", "attribList"),
    "glXCreateNewContext": ("dpy", "config", "renderType", "shareList", "direct"),
    "glXSelectEvent": ("dpy", "drawable", "mask"), "glXGetSelectedEvent": ("dpy", "drawable", "mask"),
    "glXBindTexImageEXT": ("display", "drawable", "buffer", "attrib_list"),
    "glXReleaseTexImageEXT": ("display", "drawable", "buffer"),
    "wglCreateContext": ("hdc",), "wglDeleteContext": ("hglrc",), "wglMakeCurrent": ("hdc", "hglrc"),
    "wglShareLists": ("hglrc1", "hglrc2"), "wglCreateLayerContext": ("hdc", "iLayerPlane"),
    "wglDescribeLayerPlane": ("hdc", "iPixelFormat", "iLayerPlane", "nBytes", "plpd"),
    "wglSwapLayerBuffers": ("hdc", "fuPlanes"),
    "wglUseFontBitmapsA": ("hdc", "first", "count", "listBase"),
    "wglUseFontBitmapsW": ("hdc", "first", "count", "listBase"),
    "wglUseFontOutlinesA": ("hdc", "first", "count", "listBase", "deviation", "extrusion", "format", "lpgmf"),
    "wglUseFontOutlinesW": ("hdc", "first", "count", "listBase", "deviation", "extrusion", "format", "lpgmf"),
    "wglEnumerateVideoDevicesNV": ("hDC", "phDeviceList"),
    "wglBindVideoDeviceNV": ("hDC", "uVideoSlot", "hVideoDevice", "piAttribList"),
}
# The window-system functions apitrace 11.1 records that no registry has
# (GDI's pixel-format calls it records under wgl names among them), and
# macOS's buffer swap.
APITRACE_ONLY = {
    "glXAllocateMemoryNV": ("size", "readfreq", "writefreq", "priority"), "glXFreeMemoryNV": ("pointer",),
    "eglGetSyncValuesCHROMIUM": ("dpy", "surface", "ust", "msc", "sbc"),
    "wglChoosePixelFormat": ("hdc", "ppfd"), "wglDescribePixelFormat": ("hdc", "iPixelFormat", "nBytes", "ppfd"),
    "wglGetPixelFormat": ("hdc",), "wglSetPixelFormat": ("hdc", "iPixelFormat", "ppfd"), "wglSwapBuffers": ("hdc",),
    "wglSwapMultipleBuffers": ("n", "ps"), "CGLFlushDrawable": ("ctx",),
}

# A prototype and a value as the EGL headers write them.
EGL_PROTOTYPE = re.compile(r"^EGLAPI\s[^;(]*?\bEGLAPIENTRY\s+(egl\w+)\s*\(([^)]*)\)\s*;", re.M)
EGL_DEFINE = re.compile(r"^#define\s+(EGL_\w+)\s+(?:EGL_CAST\(\w+,\s*)?(-?0x[0-9A-Fa-f]+|-?\d+)[uUlL]*\)?\s*$", re.M)
PARAMETER_NAME = re.compile(r"(\w+)\s*(?:\[\w*\])?\s*$")


# The context attributes apitrace writes as a Bool ("False", "True"; its
# glxapi.py; EGL's EGLBoolean ones it writes by name, EGL_TRUE).
BOOL_ATTRIBUTES = ("GLX_CONTEXT_OPENGL_NO_ERROR_ARB",)


def _bool(x):
    """A Bool attribute's value (GLX_CONTEXT_OPENGL_NO_ERROR_ARB's) as 0 or
    1, given as apitrace writes it ("False", "True") or as Python's bool (a
    reduced capture written by hand); None for anything else."""
    if type(x) is bool:
        return int(x)
    return {"False": 0, "True": 1}.get(x) if type(x) is str else None


def _read_xml(path, commands, values):
    root = ET.parse(path).getroot()
    for e in root.iter("enum"):
        try:
            values.setdefault(e.get("name"), int(e.get("value", ""), 0))
        except (TypeError, ValueError):
            pass
    for c in root.find("commands").iter("command"):
        commands[c.findtext("proto/name")] = tuple(p.findtext("name") for p in c.findall("param"))


def _read_header(path, commands, values):
    with open(path, encoding="utf-8") as f:
        text = f.read()
    for m in EGL_DEFINE.finditer(text):
        values.setdefault(m.group(1), int(m.group(2), 0))
    for m in EGL_PROTOTYPE.finditer(text):
        params = m.group(2).strip()
        names = () if params in ("", "void") else tuple(PARAMETER_NAME.search(p).group(1) for p in params.split(","))
        commands[m.group(1)] = names


class WindowRegistry:
    def __init__(self):
        self.commands, self.values = {}, {}
        for path in XML_REGISTRIES:
            try:
                _read_xml(path, self.commands, self.values)
            except FileNotFoundError:
                raise ToolError(f"the window system's registry {path} is missing "
                                "(scripts/setup.sh --gl installs khronos-api)") from None
            except (OSError, ET.ParseError, AttributeError, ValueError) as e:
                raise ToolError(f"the window system's registry {path} cannot be read ({e})") from None
        self.egl = None   # (read when an EGL call needs it)

    def _egl(self):
        if self.egl is None:
            commands, values = {}, {}
            for path in EGL_HEADERS:
                try:
                    _read_header(path, commands, values)
                except FileNotFoundError:
                    raise ToolError(f"EGL's header {path} is missing (scripts/setup.sh --gl installs libegl-dev)") \
                        from None
                except (OSError, UnicodeDecodeError, AttributeError, ValueError) as e:
                    raise ToolError(f"EGL's header {path} cannot be read ({e})") from None
            if "eglMakeCurrent" not in commands or "EGL_OPENGL_API" not in values:
                raise ToolError(f"EGL's header {EGL_HEADERS[0]} has no eglMakeCurrent or EGL_OPENGL_API")
            self.egl = commands, values
        return self.egl

    def signature(self, name):
        """The parameters apitrace records of window-system function `name`
        (a name with glX, egl or wgl before it, or CGLFlushDrawable), or
        None where apitrace records no such function."""
        if name in APITRACE_ONLY:
            return APITRACE_ONLY[name]
        commands = self._egl()[0] if name.startswith("egl") else self.commands
        params = commands.get(name)
        return APITRACE_NAMES.get(name, params) if params is not None else None

    def value(self, x):
        """An enumerant of the window system by value: an int as it is, a
        name (GLX_..., EGL_..., WGL_...) by the registry's value, a tuple of
        names and at most one int (apitrace's form of a bit mask: the flags
        it names, the bits it does not) their bits together; None for
        anything else or a name no registry has."""
        if type(x) is int:
            return x
        if isinstance(x, str):
            values = self._egl()[1] if x.startswith("EGL_") else self.values
            return values.get(x)
        if type(x) is tuple and sum(type(b) is int for b in x) <= 1 and all(type(b) in (str, int) for b in x):
            bits = [self.value(b) for b in x]
            if all(b is not None for b in bits):
                out = 0
                for b in bits:
                    out |= b
                return out
        return None

    def attributes(self, attrs, end):
        """A window system's attribute list (apitrace's flat list of
        attributes and values, up to the attribute `end`, GLX's 0 or
        EGL_NONE, or the list's end; None, a NULL list, has none) as
        {attribute by value: value by value}, the last of an attribute
        given twice, as Mesa's parsers keep it (a Bool value as 0 or 1). Raises ValueError, saying what, for a list of
        anything else than enumerants (by name or by value) and integers."""
        if attrs is None:
            return {}
        if not isinstance(attrs, list):
            raise ValueError(f"is {printable(attrs, 40)}, not a list")
        out = {}
        bools = {self.value(n) for n in BOOL_ATTRIBUTES}
        for i, x in enumerate(attrs):
            # (a Bool's "True" or "False" only as the value of a Bool attribute)
            if self.value(x) is None and not (i % 2 and _bool(x) is not None and self.value(attrs[i - 1]) in bools):
                raise ValueError(f"holds {printable(repr(x), 40)}, neither a number nor the name of an enumerant "
                                 "the window system has" + (" (nor the value of a Bool attribute)" if i % 2 else ""))
        for k, v in zip(attrs[0::2], attrs[1::2]):
            if self.value(k) == self.value(end):
                break
            out[self.value(k)] = self.value(v) if _bool(v) is None else _bool(v)
        return out


_REGISTRY = None


def window_registry():
    global _REGISTRY
    if _REGISTRY is None:
        _REGISTRY = WindowRegistry()
    return _REGISTRY


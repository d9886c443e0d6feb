"""The OpenGL registry (Khronos' gl.xml, Debian's khronos-api) as the converter
reads it: each command's parameters in order (apitrace's name, C type,
enumerant group, a fixed array length), and the enumerants of each group by
value. Two uses:

- an enumerant given by value where apitrace writes its name (a reduced
  capture altered by hand, glCullFace(1028)) is the enumerant of that
  value among those GL takes there, as the driver takes it
  (named_enumerants);
- a reduced capture's record must name the function's parameters as
  apitrace does, every one once and no other, in any order, and give each
  fixed-length array its length (reduced.in_order).

Parsing gl.xml takes about 0.4 s; what is read of it is kept in the user's
cache folder ($XDG_CACHE_HOME/rbcd, else ~/.cache/rbcd: matplotlib keeps
its font list so), keyed by the registry's size and time and this
module's own digest, its content checked against the SHA-256 digest
written before it, and read back in milliseconds. A cache that cannot be
written, read or checked is rebuilt, never an error; caches of another
key are removed when one is written."""
import hashlib
import json
import os
import stat
import tempfile
import xml.etree.ElementTree as ET

from .errors import ToolError

REGISTRY = "/usr/share/khronos-api/gl.xml"
CACHE_FORMAT = 4   # (one more when the file or what _parse keeps changes: VENDOR_SUFFIXES, SUFFIX_RANK, LENGTHS_DIFFER)

# apitrace's parameter names where they differ from the registry's
# (apitrace 11.1's specs/glapi.py, Debian's): a capture's calls, and so a
# reduced capture's, carry these (glDrawArraysInstancedBaseInstanceEXT and
# glGetArrayObjectivATI of another count in the registry of 2022).
APITRACE_NAMES = {
    "glAreProgramsResidentNV": ("n", "ids", "residences"), "glBindProgramNV": ("target", "program"),
    "glBlendFuncSeparateOES": ("sfactorRGB", "dfactorRGB", "sfactorAlpha", "dfactorAlpha"),
    "glClipPlanef": ("plane", "equation"),
    "glColorTableEXT": ("target", "internalformat", "width", "format", "type", "table"),
    "glCurrentPaletteMatrixOES": ("index",), "glDepthRange": ("zNear", "zFar"), "glDepthRangex": ("zNear", "zFar"),
    "glDrawArraysInstancedANGLE": ("mode", "first", "count", "instancecount"),
    "glDrawArraysInstancedARB": ("mode", "first", "count", "instancecount"),
    "glDrawArraysInstancedBaseInstanceEXT": ("mode", "first", "count", "instancecount", "baseinstance"),
    "glDrawArraysInstancedEXT": ("mode", "first", "count", "instancecount"),
    "glDrawElementsInstancedEXT": ("mode", "count", "type", "indices", "instancecount"),
    "glDrawBuffer": ("mode",),
    "glDrawElementsInstancedANGLE": ("mode", "count", "type", "indices", "instancecount"),
    "glDrawElementsInstancedARB": ("mode", "count", "type", "indices", "instancecount"),
    "glFogxv": ("pname", "params"),
    "glFrustumf": ("left", "right", "bottom", "top", "zNear", "zFar"),
    "glFrustumx": ("left", "right", "bottom", "top", "zNear", "zFar"),
    "glGetActiveSubroutineName": ("program", "shadertype", "index", "bufsize", "length", "name"),
    "glGetActiveSubroutineUniformName": ("program", "shadertype", "index", "bufsize", "length", "name"),
    "glGetActiveUniformARB": ("programObj", "index", "bufSize", "length", "size", "type", "name"),
    "glGetArrayObjectivATI": ("array", "pname", "params"),
    "glGetAttachedShaders": ("program", "maxCount", "count", "obj"), "glGetBooleanv": ("pname", "params"),
    "glGetCoverageModulationTableNV": ("bufsize", "v"),
    "glGetDebugMessageLog": ("count", "bufsize", "sources", "types", "ids", "severities", "lengths", "messageLog"),
    "glGetDebugMessageLogAMD": ("count", "bufsize", "categories", "severities", "ids", "lengths", "message"),
    "glGetDebugMessageLogARB": ("count", "bufsize", "sources", "types", "ids", "severities", "lengths", "messageLog"),
    "glGetDebugMessageLogKHR": ("count", "bufsize", "sources", "types", "ids", "severities", "lengths", "messageLog"),
    "glGetDoublei_vEXT": ("target", "index", "data"), "glGetDoublev": ("pname", "params"),
    "glGetFloati_vEXT": ("target", "index", "data"), "glGetFloatv": ("pname", "params"),
    "glGetInteger64v": ("pname", "params"), "glGetIntegerv": ("pname", "params"),
    "glGetInternalformati64v": ("target", "internalformat", "pname", "bufSize", "params"),
    "glGetInternalformativ": ("target", "internalformat", "pname", "bufSize", "params"),
    "glGetPointeri_vEXT": ("target", "index", "data"),
    "glGetProgramResourcefvNV": ("program", "programInterface", "index", "propCount", "props", "bufSize", "length",
                                 "params"),
    "glGetProgramResourceiv": ("program", "programInterface", "index", "propCount", "props", "bufSize", "length",
                               "params"),
    "glGetShaderSourceARB": ("obj", "bufSize", "length", "source"),
    "glGetSynciv": ("sync", "pname", "bufSize", "length", "values"),
    "glGetSyncivAPPLE": ("sync", "pname", "bufSize", "length", "values"),
    "glGetTranslatedShaderSourceANGLE": ("shader", "bufsize", "length", "source"), "glIsProgramNV": ("program",),
    "glLightModelxv": ("pname", "params"), "glMaterialxv": ("face", "pname", "params"),
    "glMultiDrawArraysEXT": ("mode", "first", "count", "drawcount"),
    "glMultiDrawArraysIndirectAMD": ("mode", "indirect", "drawcount", "stride"),
    "glMultiDrawElementArrayAPPLE": ("mode", "first", "count", "drawcount"),
    "glMultiDrawElementsEXT": ("mode", "count", "type", "indices", "drawcount"),
    "glMultiDrawElementsIndirectAMD": ("mode", "type", "indirect", "drawcount", "stride"),
    "glMultiDrawRangeElementArrayAPPLE": ("mode", "start", "end", "first", "count", "drawcount"),
    "glMultiModeDrawArraysIBM": ("mode", "first", "count", "drawcount", "modestride"),
    "glMultiModeDrawElementsIBM": ("mode", "count", "type", "indices", "drawcount", "modestride"),
    "glMultiTexCoord4x": ("target", "s", "t", "r", "q"),
    "glOrthof": ("left", "right", "bottom", "top", "zNear", "zFar"),
    "glOrthox": ("left", "right", "bottom", "top", "zNear", "zFar"),
    "glPointSizePointerOES": ("type", "stride", "ptr"),
    "glProgramBufferParametersIivNV": ("target", "buffer", "index", "count", "params"),
    "glProgramBufferParametersIuivNV": ("target", "buffer", "index", "count", "params"),
    "glProgramBufferParametersfvNV": ("target", "buffer", "index", "count", "params"),
    "glReadBuffer": ("mode",), "glSampleMaski": ("index", "mask"),
    "glShaderBinary": ("count", "shaders", "binaryformat", "binary", "length"),
    "glTexPageCommitmentARB": ("target", "level", "xoffset", "yoffset", "zoffset", "width", "height", "depth",
                               "resident"),
    "glTextureParameterfv": ("texture", "pname", "params"), "glTextureParameteriv": ("texture", "pname", "params"),
    "glVDPAUGetSurfaceivNV": ("surface", "pname", "bufSize", "length", "values"),
    "glVertexAttribPointerNV": ("index", "size", "type", "stride", "pointer"),
}
# The GL functions apitrace 11.1 records that the registry of 2022 lacks
# (any other name of GL's form is no GL function).
APITRACE_ONLY = {
    "glAddSwapHintRectWIN": ("x", "y", "width", "height"), "glBeginQueryANGLE": ("target", "id"),
    "glBlendEquationSeparateATI": ("equationRGB", "equationAlpha"), "glBufferRegionEnabled": (),
    "glDeleteBufferRegion": ("region",), "glDeleteQueriesANGLE": ("n", "ids"),
    "glDrawBufferRegion": ("region", "x", "y", "width", "height", "xDest", "yDest"), "glEndQueryANGLE": ("target",),
    "glFinishRenderAPPLE": (), "glFlushRenderAPPLE": (), "glGenQueriesANGLE": ("n", "ids"),
    "glGetQueryObjecti64vANGLE": ("id", "pname", "params"), "glGetQueryObjectivANGLE": ("id", "pname", "params"),
    "glGetQueryObjectui64vANGLE": ("id", "pname", "params"), "glGetQueryObjectuivANGLE": ("id", "pname", "params"),
    "glGetQueryivANGLE": ("target", "pname", "params"), "glIsQueryANGLE": ("id",), "glNewBufferRegion": ("type",),
    "glPNTrianglesfATIX": ("pname", "param"), "glPNTrianglesiATIX": ("pname", "param"),
    "glPointSizePointerAPPLE": ("type", "stride", "pointer"), "glQueryCounterANGLE": ("id", "target"),
    "glReadBufferRegion": ("region", "x", "y", "width", "height"), "glSwapAPPLE": (),
    "glVertexPointSizefAPPLE": ("size",)}
# Fixed array lengths apitrace writes otherwise than the registry states.
LENGTHS_DIFFER = {"glDrawTexfvOES", "glDrawTexivOES", "glDrawTexsvOES", "glDrawTexxvOES"}
VENDOR_SUFFIXES = ("_ARB", "_EXT", "_KHR", "_OES", "_NV", "_AMD", "_APPLE", "_ATI", "_SGIX", "_SGIS", "_IMG",
                   "_INTEL", "_MESA", "_QCOM", "_ANGLE", "_IBM", "_SUN", "_3DFX", "_OML", "_HP", "_PGI", "_WIN",
                   "_SGI", "_REND", "_INGR", "_ARM", "_MESAX", "_OVR", "_NVX", "_S3", "_DMP", "_FJ", "_VIV", "_GREMEDY")


# The vendor suffixes apitrace's names carry where a value has no core name,
# most often first (its table lists the registry's names in their order,
# EXT_texture_compression_s3tc's _EXT before ANGLE's aliases).
SUFFIX_RANK = ("_EXT", "_ARB", "_KHR", "_OES")


def _rank(name, order):
    """A name's place among a value's names: core names first, then by
    SUFFIX_RANK, then in the registry's order."""
    if not name.endswith(VENDOR_SUFFIXES):
        return (0, order)
    return (1 + next((i for i, sfx in enumerate(SUFFIX_RANK) if name.endswith(sfx)), len(SUFFIX_RANK)), order)


def _parse(path):
    """The registry's commands, {name: [[apitrace's name, C type, group,
    length], ...]}, and enumerants, {group: [[value, name], ...]}, bitmasks
    left out. A value is named in a group by the best (_rank) of its names
    the registry puts in that group, each taken by its core form where the
    value has one (gl.xml tags GL_TEXTURE_3D_EXT, not GL_TEXTURE_3D, as a
    capability); the group "" holds the values with one core name, or none
    and a best other, whatever their groups."""
    root = ET.parse(path).getroot()
    by_value = {}   # value: [(name, groups)], in the registry's order
    for block in root.iter("enums"):
        if block.get("type") == "bitmask":
            continue
        for e in block.iter("enum"):
            try:
                v = int(e.get("value", ""), 0)
            except ValueError:
                continue
            if 0 <= v < 1 << 32 and e.get("name"):
                by_value.setdefault(v, []).append((e.get("name"), (e.get("group") or "").split(",")))
    groups = {}
    for v, names in by_value.items():
        order = {}
        for n, _ in names:
            order.setdefault(n, len(order))
        core = [n for n in order if not n.endswith(VENDOR_SUFFIXES)]
        if len(core) == 1 or not core:
            groups.setdefault("", []).append([v, min(order, key=lambda n: _rank(n, order[n]))])

        def core_form(n):
            base = n.rsplit("_", 1)[0] if n.endswith(VENDOR_SUFFIXES) else n
            return base if base in order else n
        best = {}
        for n, gs in names:
            n = core_form(n)
            for g in gs:
                if g and (g not in best or _rank(n, order[n]) < _rank(best[g], order[best[g]])):
                    best[g] = n
        for g, n in best.items():
            groups.setdefault(g, []).append([v, n])
    commands = {}
    for c in root.find("commands").iter("command"):
        name = c.findtext("proto/name")
        params = []
        for p in c.findall("param"):
            text = "".join(p.itertext())
            length = p.get("len", "")
            params.append([p.findtext("name"), p.findtext("ptype"), p.get("group"),
                           int(length) if length.isdigit() and int(length) > 1 and text.lstrip().startswith("const")
                           and name not in LENGTHS_DIFFER else None])
        commands[name] = params
    return {"format": CACHE_FORMAT, "commands": commands, "groups": groups}


# A cache file past this size is not the converter's (about 0.6 MB): not read.
CACHE_MAX_BYTES = 16 << 20


def _code_digest():
    """The first digits of this module's own SHA-256: a cache is read only
    by the code that wrote it (another build of the converter may read
    the registry otherwise under the same CACHE_FORMAT)."""
    try:
        with open(__file__, "rb") as f:
            return hashlib.sha256(f.read()).hexdigest()[:16]
    except OSError:
        return "unknown"


def _cache_path(st):
    """The cache file for a registry of stat `st`, or None where the user
    has no cache folder (no HOME and no entry in the password database)."""
    home = os.environ.get("XDG_CACHE_HOME", "")
    if not os.path.isabs(home):   # (the XDG rule: a relative path is ignored)
        home = os.path.join(os.path.expanduser("~"), ".cache")
    if not os.path.isabs(home):
        return None
    return os.path.join(home, "rbcd", f"gl-registry-{CACHE_FORMAT}-{_code_digest()}-{st.st_size}-{st.st_mtime_ns}.json")


def _read_cache(cache):
    """The cached registry, or None where there is none usable: not a
    regular file (a FIFO is never waited on), too large, not the SHA-256
    digest _load wrote before its JSON (an edit by hand, a file cut short),
    or not of the shapes _parse makes."""
    try:
        fd = os.open(cache, os.O_RDONLY | os.O_NONBLOCK | os.O_CLOEXEC)
    except OSError:
        return None
    try:
        with os.fdopen(fd, "rb") as f:
            st = os.fstat(f.fileno())
            # (another user's file, in a folder others may write, is not ours)
            if not stat.S_ISREG(st.st_mode) or st.st_size > CACHE_MAX_BYTES or st.st_uid != os.getuid():
                return None
            digest, _, body = f.read(CACHE_MAX_BYTES + 1).partition(b"\n")
        # (a file edited by hand, or cut short, is not what was written)
        if digest != hashlib.sha256(body).hexdigest().encode():
            return None
        data = json.loads(body)
        if not (isinstance(data, dict) and data.get("format") == CACHE_FORMAT):
            return None
        commands, groups = data.get("commands"), data.get("groups")
        if not (isinstance(commands, dict) and isinstance(groups, dict)):
            return None
        for params in commands.values():
            if not isinstance(params, list) or not all(
                    isinstance(p, list) and len(p) == 4 and isinstance(p[0], str)
                    and all(isinstance(x, (str, type(None))) for x in p[1:3])
                    and (p[3] is None or type(p[3]) is int) for p in params):
                return None
        for pairs in groups.values():
            if not isinstance(pairs, list) or not all(
                    isinstance(x, list) and len(x) == 2 and type(x[0]) is int and isinstance(x[1], str) for x in pairs):
                return None
        # What every registry holds (a cache cut down, or of another
        # registry's making, is not this one's).
        if len(commands) < 2000 or commands.get("glDrawArrays", [[None]])[0][:3] != ["mode", "GLenum", "PrimitiveType"] \
                or [4, "GL_TRIANGLES"] not in groups.get("PrimitiveType", []):
            return None
        return data
    except (OSError, ValueError, RecursionError, IndexError, TypeError):
        return None   # (IndexError, TypeError: a sentinel entry of another shape)


def _load():
    try:
        st = os.stat(REGISTRY)
    except OSError:
        raise ToolError(f"the OpenGL registry {REGISTRY} is missing (scripts/setup.sh --gl installs khronos-api)") \
            from None
    cache = _cache_path(st)
    data = _read_cache(cache) if cache else None
    if data is not None:
        return data
    try:
        data = _parse(REGISTRY)
    except (OSError, ET.ParseError, AttributeError, ValueError) as e:
        raise ToolError(f"the OpenGL registry {REGISTRY} cannot be read ({e})") from None
    if cache is None:
        return data
    tmp = None
    try:
        os.makedirs(os.path.dirname(cache), mode=0o700, exist_ok=True)
        body = json.dumps(data, separators=(",", ":")).encode()
        with tempfile.NamedTemporaryFile("wb", dir=os.path.dirname(cache), suffix=".tmp", delete=False) as f:
            tmp = f.name
            f.write(hashlib.sha256(body).hexdigest().encode() + b"\n" + body)
        os.replace(tmp, cache)
        # Caches of another registry or another build of this code are
        # never read again: removed (about 0.7 MB each).
        folder = os.path.dirname(cache)
        for other in os.listdir(folder):
            if other.startswith("gl-registry-") and other.endswith(".json") and other != os.path.basename(cache):
                os.unlink(os.path.join(folder, other))
    except OSError:
        if tmp is not None:
            try:
                os.unlink(tmp)
            except OSError:
                pass
    return data


class Registry:
    def __init__(self, data):
        self.commands = data["commands"]
        self.groups = {g: {int(v): n for v, n in pairs} for g, pairs in data["groups"].items()}
        self.signatures = {}

    def signature(self, name):
        """The function's parameters as apitrace writes them: ((name, C
        type, group, fixed length), ...), only the names of APITRACE_ONLY's,
        or None where neither has the function (the window system's:
        window_registry)."""
        sig = self.signatures.get(name, False)
        if sig is False:
            params = self.commands.get(name)
            names = APITRACE_NAMES.get(name)
            if params is not None and names is not None and len(names) != len(params):
                # (the registry's count wrong: the core form's types)
                core = self.commands.get(name[:-3])
                params = core if core is not None and len(core) == len(names) else None
            if params is not None:
                sig = tuple((names[i] if names else p[0], p[1], p[2], p[3]) for i, p in enumerate(params))
            elif name in APITRACE_ONLY:
                sig = tuple((k, None, None, None) for k in APITRACE_ONLY[name])
            else:
                sig = None
            self.signatures[name] = sig
        return sig

    def enumerant(self, group, value, fallback=True):
        """The enumerant of `value` among those of `group` (a parameter's),
        by name; else, `fallback`, its one core name, if it has one; else
        None."""
        named = self.groups.get(group) if group else None
        name = named.get(value) if named else None
        return name if name is not None or not fallback else self.groups.get("", {}).get(value)


_REGISTRY = None


def registry():
    global _REGISTRY
    if _REGISTRY is None:
        _REGISTRY = Registry(_load())
    return _REGISTRY


def named_enumerants(name, args):
    """`args` (apitrace's (name, value) pairs) with each enumerant given by
    value named as apitrace names it (Registry.enumerant): a GLenum
    argument, each of a GLenum list (glDrawBuffers'), and a GLint one the
    registry gives a group (glTexImage2D's internalformat, which apitrace
    writes by name; only within the group: 3 there is a component count).
    A value with no name stays a number (GL_INVALID_ENUM where it is read).
    Costs a scan of the arguments when none is a number."""
    if not any(type(v) is int or type(v) is list for _, v in args):
        return args
    sig = registry().signature(name)
    if sig is None:
        return args
    by_name = {p[0]: p for p in sig}
    # By name; by position where no argument has one of the function's
    # names and there are as many (a caller's own numbering: the unit tests).
    positional = len(args) == len(sig) and not any(k in by_name for k, _ in args)
    out = None
    for i, (k, v) in enumerate(args):
        p = sig[i] if positional else by_name.get(k)
        if p is None or not (p[1] == "GLenum" or p[1] == "GLint" and p[2]):
            continue
        fallback = p[1] == "GLenum"
        if type(v) is int:
            n = registry().enumerant(p[2], v, fallback) if 0 <= v < 1 << 32 else None
        elif type(v) is list and fallback and any(type(x) is int for x in v):
            n = [registry().enumerant(p[2], x, fallback) or x if type(x) is int and 0 <= x < 1 << 32 else x
                 for x in v]
        else:
            continue
        if n is not None:
            if out is None:
                out = list(args)
            out[i] = (k, n)
    return out if out is not None else args

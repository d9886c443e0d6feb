"""Selection files: which draws of an unmodified program are collisionable
objects (docs/gl-capture.md, "Identified off line")."""
import re
import tomllib

from ..cli import U32, U63, UsageError, integer, parse_toml, read_input, real
from .errors import ConvertError, printable

# ---------------------------------------------------------------- the selection file

class Selection:
    """Rules that say which draws of an unmodified program are collisionable
    objects (docs/gl-capture.md, "Identified off line"). Each [[object]] rule
    names an id and any of: calls = [A, B] (a call range), vertex_count =
    [MIN, MAX], texture = [names], modelview = "translation-not-identity" ...
    The first rule that matches a draw decides; [[exclude]] rules first."""

    KEYS = {"id", "name", "calls", "frames", "vertex_count", "texture", "depth_write", "group_by",
            "projection", "modelview_differs_from_view", "min_screen_area", "max_screen_area",
            "program", "pass", "instances", "group_instances", "texture_image", "vertex_data", "draw_index"}

    # [MIN, MAX] rules: each bound within what the draw's value can be. Call
    # and frame numbers as a capture numbers them (from 0, below 2^63: a
    # reduced capture's call numbers are checked so); vertex counts, instance
    # counts and draw indices within GL's unsigned 32-bit values.
    RANGES = {"calls": U63[1], "frames": U63[1], "vertex_count": U32[1], "instances": U32[1],
              "draw_index": U32[1]}

    def __init__(self, path):
        self.path = path
        try:
            # A regular file of at most 1 MiB, opened without waiting on a FIFO,
            # its keys of at most 64 dotted parts (rbcd.cli.parse_toml).
            data = read_input(path, "the selection file", 1 << 20)
            doc = parse_toml(path, data.decode("utf-8"))
        except UsageError as e:
            raise ConvertError(str(e)) from None
        except UnicodeDecodeError as e:
            raise ConvertError(f"{path}: not UTF-8 text (byte {e.start})")
        except tomllib.TOMLDecodeError as e:
            raise ConvertError(f"{path}: {printable(e)}")
        except RecursionError:
            raise ConvertError(f"{path}: nested too deep to read")
        unknown = set(doc) - {"object", "exclude", "settings"}
        if unknown:
            raise ConvertError(f"{path}: unknown table or key '{printable(sorted(unknown)[0])}'")
        self.settings = doc.get("settings", {})
        if not isinstance(self.settings, dict):
            raise ConvertError(f"{path}: settings must be a table")
        self.settings = self.check_settings(path, self.settings)
        self.rules = []
        for kind in ("exclude", "object"):
            entries = doc.get(kind, [])
            if not isinstance(entries, list):
                raise ConvertError(f"{path}: {kind} must be an array of tables ([[{kind}]])")
            for i, r in enumerate(entries):
                where = f"{path}: {kind}[{i}]"
                if not isinstance(r, dict):
                    raise ConvertError(f"{where}: must be a table")
                self.check_rule(where, kind, r)
                self.rules.append((kind, r))
        # A draw's vertex data is hashed only when a rule names it.
        self.names_vertex_data = any("vertex_data" in r for _, r in self.rules)
        self.last_rule = {}

    @staticmethod
    def check_settings(path, settings):
        """The entity tracker's settings, checked and with their defaults."""
        out = {"first_entity_id": 1, "max_entity_id": 127, "track_radius": 48.0, "part_horizontal": 16.0,
               "part_vertical": 64.0, "up_axis": "z", "origin_attribute": 8}
        for k, v in settings.items():
            where = f"{path}: settings.{printable(k)}"
            if k not in out:
                raise ConvertError(f"{where}: unknown key")
            try:
                if k == "up_axis":
                    if v not in ("x", "y", "z"):
                        raise ConvertError(f"{where}: must be \"x\", \"y\" or \"z\"")
                elif k.endswith("_id"):
                    v = integer(v, where, *U32)
                elif k == "origin_attribute":
                    v = integer(v, where, 0, 31)
                else:
                    v = real(v, where, 0.0, 1e30)
            except UsageError as e:
                raise ConvertError(str(e)) from None
            out[k] = v
        if out["first_entity_id"] > out["max_entity_id"]:
            raise ConvertError(f"{path}: settings.first_entity_id is above settings.max_entity_id")
        return out

    def check_rule(self, where, kind, r):
        for k in r:
            if k not in self.KEYS:
                raise ConvertError(f"{where}.{printable(k)}: unknown key")
        if "group_by" in r and r["group_by"] not in ("modelview", "instance_origin"):
            raise ConvertError(f"{where}.group_by: must be \"modelview\" or \"instance_origin\"")
        if kind == "object":
            if "id" not in r and "group_by" not in r:
                raise ConvertError(f"{where}: needs id (or group_by)")
            if "id" in r and "group_by" in r:
                raise ConvertError(f"{where}: id and group_by both given (group_by gives the ids: one or the other)")
        else:
            for k in ("id", "group_by"):
                if k in r:
                    raise ConvertError(f"{where}.{k}: an exclude rule gives no id (it keeps draws out)")
        if "id" in r and (not isinstance(r["id"], int) or isinstance(r["id"], bool)
                          or not U32[0] <= r["id"] <= U32[1]):
            raise ConvertError(f"{where}.id: must be an integer in [0, {U32[1]}]")
        for k, top in self.RANGES.items():
            if k in r:
                v = r[k]
                if (not isinstance(v, list) or len(v) != 2 or
                        not all(isinstance(x, int) and not isinstance(x, bool) and 0 <= x <= top for x in v)
                        or v[0] > v[1]):
                    raise ConvertError(f"{where}.{k}: must be [MIN, MAX], integers in [0, {top}], MIN <= MAX")
        if "texture" in r and not (isinstance(r["texture"], list) and all(
                isinstance(x, int) and not isinstance(x, bool) and U32[0] <= x <= U32[1] for x in r["texture"])):
            raise ConvertError(f"{where}.texture: must be a list of texture names (integers in [0, {U32[1]}])")
        if "program" in r and not (isinstance(r["program"], list) and r["program"] and all(
                isinstance(x, str) and re.fullmatch(r"[0-9a-f]{8,64}", x) for x in r["program"])):
            raise ConvertError(f"{where}.program: must be a list of program digests (8 to 64 lower-case hex "
                               "digits, as --list-draws shows them)")
        if "name" in r and not isinstance(r["name"], str):
            raise ConvertError(f"{where}.name: must be a string")
        for k, what in (("texture_image", "texture image"), ("vertex_data", "vertex data")):
            if k in r and not (isinstance(r[k], list) and r[k] and all(
                    isinstance(x, str) and re.fullmatch(r"[0-9a-f]{8,16}", x) for x in r[k])):
                raise ConvertError(f"{where}.{k}: must be a list of {what} digests (8 to 16 "
                                   "lower-case hex digits, as --list-draws shows them)")
        if "pass" in r and not (isinstance(r["pass"], list) and r["pass"] and
                                all(isinstance(x, str) for x in r["pass"])):
            raise ConvertError(f"{where}.pass: must be a list of pass names (strings)")
        if "projection" in r and r["projection"] not in ("perspective", "orthographic"):
            raise ConvertError(f"{where}.projection: must be \"perspective\" or \"orthographic\"")
        for k in ("depth_write", "modelview_differs_from_view", "group_instances"):
            if k in r and not isinstance(r[k], bool):
                raise ConvertError(f"{where}.{k}: must be true or false")
        for k in ("min_screen_area", "max_screen_area"):
            if k in r:
                try:
                    real(r[k], f"{where}.{k}", 0.0)   # (pixels: a negative area matches nothing, or everything)
                except UsageError as e:
                    raise ConvertError(str(e)) from None
        if r.get("min_screen_area", 0) > r.get("max_screen_area", float("inf")):
            raise ConvertError(f"{where}: min_screen_area is above max_screen_area (no draw matches)")

    @staticmethod
    def matches(r, d):
        if "calls" in r and not (r["calls"][0] <= d["call"] <= r["calls"][1]):
            return False
        if "frames" in r and not (r["frames"][0] <= d["frame"] <= r["frames"][1]):
            return False
        if "vertex_count" in r and not (r["vertex_count"][0] <= d["vertices"] <= r["vertex_count"][1]):
            return False
        if "texture" in r and d["texture"] not in r["texture"]:
            return False
        if "program" in r and not any(d["program"].startswith(p) for p in r["program"]):
            return False
        for k in ("texture_image", "vertex_data"):
            if k in r and not (d[k] and any(d[k].startswith(p) for p in r[k])):
                return False
        if "pass" in r and d["pass"] not in r["pass"]:
            return False
        if "instances" in r and not (r["instances"][0] <= d["instances"] <= r["instances"][1]):
            return False
        if "draw_index" in r and not (r["draw_index"][0] <= d["draw_index"] <= r["draw_index"][1]):
            return False
        if "depth_write" in r and r["depth_write"] != d["depth_write"]:
            return False
        if "projection" in r and r["projection"] != d["projection"]:
            return False
        if "modelview_differs_from_view" in r and r["modelview_differs_from_view"] != d["own_modelview"]:
            return False
        if "min_screen_area" in r and d["screen_area"] < r["min_screen_area"]:
            return False
        if "max_screen_area" in r and d["screen_area"] > r["max_screen_area"]:
            return False
        return True

    def classify(self, d):
        """(object id or None, rule name) for draw description d."""
        for kind, r in self.rules:
            if self.matches(r, d):
                self.last_rule = r
                if kind == "exclude":
                    return None, r.get("name", "exclude")
                if r.get("group_by") in ("modelview", "instance_origin"):
                    return "entity", r.get("name", "entity")
                return r["id"], r.get("name", f"id {r['id']}")
        self.last_rule = {}
        return None, "no rule"

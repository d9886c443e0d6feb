"""Selection files: which draws of an unmodified program are collisionable
objects (docs/gl-capture.md, "Identified off line")."""
import re
import tomllib

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
            "program", "pass", "instances", "group_instances"}

    def __init__(self, path):
        self.path = path
        try:
            with open(path, "rb") as f:
                data = f.read(1 << 20)
                if f.read(1):
                    raise ConvertError(f"{path}: larger than 1 MiB")
            doc = tomllib.loads(data.decode("utf-8"))
        except ConvertError:
            raise
        except (OSError, UnicodeDecodeError) as e:
            raise ConvertError(f"{path}: cannot read: {printable(e)}")
        except tomllib.TOMLDecodeError as e:
            raise ConvertError(f"{path}: {printable(e)}")
        unknown = set(doc) - {"object", "exclude", "settings"}
        if unknown:
            raise ConvertError(f"{path}: unknown table or key '{printable(sorted(unknown)[0])}'")
        self.settings = doc.get("settings", {})
        if not isinstance(self.settings, dict):
            raise ConvertError(f"{path}: settings must be a table")
        for k in self.settings:
            if k not in ("first_entity_id", "max_entity_id", "track_radius", "part_horizontal", "part_vertical",
                         "up_axis"):
                raise ConvertError(f"{path}: settings.{printable(k)}: unknown key")
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
        self.last_rule = {}

    def check_rule(self, where, kind, r):
        for k in r:
            if k not in self.KEYS:
                raise ConvertError(f"{where}.{printable(k)}: unknown key")
        if kind == "object":
            if "id" not in r and r.get("group_by") != "modelview":
                raise ConvertError(f"{where}: needs id (or group_by = \"modelview\")")
            if "id" in r and (not isinstance(r["id"], int) or isinstance(r["id"], bool) or r["id"] < 0):
                raise ConvertError(f"{where}.id: must be a non-negative integer")
        for k in ("calls", "frames", "vertex_count", "instances"):
            if k in r:
                v = r[k]
                if (not isinstance(v, list) or len(v) != 2 or
                        not all(isinstance(x, int) and not isinstance(x, bool) and x >= 0 for x in v)
                        or v[0] > v[1]):
                    raise ConvertError(f"{where}.{k}: must be [MIN, MAX], integers, MIN <= MAX")
        if "texture" in r and not (isinstance(r["texture"], list) and
                                   all(isinstance(x, int) and not isinstance(x, bool) for x in r["texture"])):
            raise ConvertError(f"{where}.texture: must be a list of texture names (integers)")
        if "program" in r and not (isinstance(r["program"], list) and r["program"] and all(
                isinstance(x, str) and re.fullmatch(r"[0-9a-f]{8,64}", x) for x in r["program"])):
            raise ConvertError(f"{where}.program: must be a list of program digests (8 to 64 lower-case hex "
                               "digits, as --list-draws shows them)")
        if "pass" in r and not (isinstance(r["pass"], list) and r["pass"] and
                                all(isinstance(x, str) for x in r["pass"])):
            raise ConvertError(f"{where}.pass: must be a list of pass names (strings)")
        if "projection" in r and r["projection"] not in ("perspective", "orthographic"):
            raise ConvertError(f"{where}.projection: must be \"perspective\" or \"orthographic\"")
        for k in ("depth_write", "modelview_differs_from_view", "group_instances"):
            if k in r and not isinstance(r[k], bool):
                raise ConvertError(f"{where}.{k}: must be true or false")
        if "group_by" in r and r["group_by"] != "modelview":
            raise ConvertError(f"{where}.group_by: must be \"modelview\"")
        for k in ("min_screen_area", "max_screen_area"):
            if k in r and not isinstance(r[k], (int, float)):
                raise ConvertError(f"{where}.{k}: must be a number")

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
        if "pass" in r and d["pass"] not in r["pass"]:
            return False
        if "instances" in r and not (r["instances"][0] <= d["instances"] <= r["instances"][1]):
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
                if r.get("group_by") == "modelview":
                    return "entity", r.get("name", "entity")
                return r["id"], r.get("name", f"id {r['id']}")
        self.last_rule = {}
        return None, "no rule"

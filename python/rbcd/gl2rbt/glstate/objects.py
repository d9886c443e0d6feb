"""Which object a draw is: the application's debug groups, or the selection rules."""
import re

import numpy as np

from ...cli import U32, integer
from ..errors import checked, fail_call

# Debug groups an application can push (Mesa: a stack of 64 with the
# default group at its bottom); a push past them is GL_STACK_OVERFLOW.
MAX_DEBUG_GROUPS = 63


def projection_of(proj, clip):
    if proj is None:
        return "orthographic" if len(clip) and np.all(clip[:, 3] == 1.0) else "perspective"
    return "perspective" if abs(proj[3, 3]) < 1e-12 else "orthographic"


class ObjectCalls:
    """Debug groups and markers, and a draw's description for the rules."""

    def note_draw(self, no, name, obj_id, nverts, mv, proj, clip):
        if self.listing is None:
            return
        d = self.describe(no, mv, proj, nverts, clip)
        box = tuple(round(v) for v in d["box"])
        self.listing.append({"index": len(self.listing), "call": no, "function": name, "vertices": nverts,
                             "texture": d["texture"], "texture_image": d["texture_image"],
                             "projection": d["projection"],
                             "own_modelview": d["own_modelview"], "depth_write": d["depth_write"],
                             "depth_func": self.s.depth_func, "box": box, "object": obj_id,
                             "program": d["program"], "pass": d["pass"], "vertex_data": d["vertex_data"],
                             "rule": self.last_rule,
                             "translation": [0.0] * 3 if mv is None else [round(float(v), 2) for v in mv[0:3, 3]]})

    def object_of(self, no, mv, proj, nverts, clip):
        self.last_rule_table = {}
        for g in reversed(self.s.groups):
            if g is not None:
                self.last_rule = "debug group"
                return g
        if self.select is None:
            self.last_rule = "untagged"
            return None
        d = self.describe(no, mv, proj, nverts, clip)
        # The draw record's index in the frame's camera pass (the records
        # before it; --list-draws numbers them so while every viewport meets
        # the screen): a program that draws its objects in one order every
        # frame (glmark2's pulsar quads) names each so.
        d["draw_index"] = self.frame_records
        obj, self.last_rule = self.select.classify(d)
        self.last_rule_table = self.select.last_rule
        if obj == "entity" and self.last_rule_table["group_by"] == "instance_origin":
            if self.draw_instance is None:
                fail_call(no, f"rule '{self.last_rule}': group_by = \"instance_origin\" needs a draw under a "
                          "program")
            origin = self.instance_origin(no, self.select.settings["origin_attribute"], self.draw_instance)
            obj = self.tracker.id_for_origin(origin, no)
        elif obj == "entity":
            if mv is None:
                fail_call(no, f"rule '{self.last_rule}': group_by = \"modelview\" needs the fixed-function "
                          "model-view; this draw is under a program")
            obj = self.tracker.id_for(mv, self.frame_view, no)
        return obj

    def describe(self, no, mv, proj, nverts, clip):
        """What selection rules and --list-draws see of a draw; mv and proj
        are None for a draw under a program, whose projection is told from
        its clip-space w (all 1: orthographic)."""
        view = getattr(self, "frame_view", None)
        x0, y0, x1, y1 = self.screen_box(clip)
        area = float((x1 - x0) * (y1 - y0))
        return {"call": no, "frame": self.frame, "vertices": nverts, "texture": self.s.texture,
                "texture_image": self.s.texture_images.get(self.s.texture) or "",
                "depth_write": self.s.depth_test and self.s.depth_mask,
                "projection": projection_of(proj, clip),
                "own_modelview": mv is not None and view is not None and not np.allclose(mv, view, atol=1e-6),
                "screen_area": area, "box": (x0, y0, x1, y1), "program": self.program_digest(),
                "pass": self.pass_name(), "instances": self.draw_instances,
                "vertex_data": self.draw_vertex_data() if self.listing is not None or self.select.names_vertex_data
                else ""}

    def screen_box(self, clip):
        """The screen pixels the box of a draw's clip-space positions covers,
        (x0, y0, x1, y1) from the screen's top left: its normalized device
        coordinates cut to the clip volume, taken through the viewport as GL
        takes them (a draw into a quarter of the screen covers a quarter of
        the pixels it would cover in the whole), then cut to the screen."""
        w, h = self.screen
        vx, vy, vw, vh = self.s.viewport or (0, 0, w, h)
        ndc = clip[:, 0:2] / np.maximum(np.abs(clip[:, 3:4]), 1e-30)
        lo, hi = np.clip(ndc.min(axis=0), -1, 1), np.clip(ndc.max(axis=0), -1, 1)
        x0, x1 = (min(max(vx + (v + 1) * vw / 2, 0.0), w) for v in (float(lo[0]), float(hi[0])))
        y0, y1 = (min(max(vy + (v + 1) * vh / 2, 0.0), h) for v in (float(lo[1]), float(hi[1])))
        return x0, h - y1, x1, h - y0

    def draw_vertex_data(self):
        """The digest rules' `vertex_data` names the current draw by (its
        instances share it): computed once a draw, when a rule or a
        listing asks."""
        if self.vertex_data is None:
            return ""
        if callable(self.vertex_data):
            self.vertex_data = self.vertex_data()
        return self.vertex_data

    def program_digest(self):
        """The digest of the sources of the program a draw runs ("" without a vertex shader)."""
        return self.draw_digest() if self.vertex_program() else ""

    def pass_name(self):
        """The innermost debug group or marker that is not an object's, else the
        last message the application inserted in the frame (a game's names for
        its passes), else ""."""
        for obj, text in reversed(self.s.group_names):
            if obj is None and text:
                return text
        return self.s.marker

    def h_push_debug_group(self, no, name, a, args):
        d = dict(args)
        if not isinstance(d.get("message"), (str, type(None))):
            fail_call(no, f"{name}: the message is not a string")
        obj = None
        if d.get("source") == "GL_DEBUG_SOURCE_APPLICATION" and d.get("message") == "rbcd-object":
            obj = checked(no, integer, d.get("id"), f"{name}: an rbcd-object group's id", *U32)
        if len(self.s.groups) >= MAX_DEBUG_GROUPS:
            return   # GL_STACK_OVERFLOW: the push does nothing
        self.s.groups.append(obj)
        self.s.group_names.append((obj, d.get("message") if isinstance(d.get("message"), str) else ""))

    def h_push_group_marker(self, no, name, a, args):
        d = dict(args)
        text = d.get("marker")
        obj = None
        if isinstance(text, str):
            length = d.get("length", 0)
            if isinstance(length, int) and length > 0:
                text = text[:length]
            m = re.fullmatch(r"rbcd-object (\d+)", text)
            if m:
                obj = checked(no, integer, int(m.group(1)), f"{name}: an rbcd-object marker's id", *U32)
        if len(self.s.groups) >= MAX_DEBUG_GROUPS:
            return   # as a debug group's push past the stack's depth: nothing
        self.s.groups.append(obj)
        self.s.group_names.append((obj, text if isinstance(text, str) else ""))

    def h_pop_group(self, no, name, a, args):
        if not self.s.groups:
            return   # GL_STACK_UNDERFLOW: the pop does nothing
        self.s.groups.pop()
        self.s.group_names.pop()

    def h_marker(self, no, name, a, args):
        """glDebugMessageInsert, glInsertEventMarkerEXT: a name for what follows."""
        d = dict(args)
        text = d.get("buf", d.get("marker"))
        if isinstance(text, str):
            length = d.get("length", -1)
            self.s.marker = text[:length] if isinstance(length, int) and length > 0 else text

    HANDLERS = {
        "glDebugMessageInsert": h_marker,
        "glInsertEventMarker": h_marker,
        "glPushDebugGroup": h_push_debug_group,
        "glPopDebugGroup": h_pop_group,
        "glPushGroupMarker": h_push_group_marker,
        "glPopGroupMarker": h_pop_group,
    }

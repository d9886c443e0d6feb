"""Objects of unmodified games, told apart by their model-view matrices and
followed across frames."""
import math

import numpy as np

from .errors import fail_call



class EntityTracker:
    """Objects for draws that rules mark group_by = "modelview" (an unmodified
    game's entities, each drawn under a model-view matrix of its own).

    Within a frame, draws under one matrix are one part, and a part joins an
    entity when its origin, in world coordinates (the frame's view matrix
    undone), lies within part_horizontal of one of the entity's parts across
    the up axis and within part_vertical along it: a player's legs, torso,
    head and weapon become one object. Across frames an entity keeps the id of
    the previous frame's entity with a part within track_radius of one of its
    own (nearest first); otherwise it takes the lowest free id. This fails,
    documented in docs/gl-capture.md, when two entities come within those
    distances of each other (they merge, or swap ids), or when an entity
    vanishes and another appears where it was in the next frame."""

    def __init__(self, settings):
        # Checked by Selection.check_settings (the defaults there too).
        self.first = settings.get("first_entity_id", 1)
        self.max_id = settings.get("max_entity_id", 127)
        self.radius = settings.get("track_radius", 48.0)
        self.horizontal = settings.get("part_horizontal", 16.0)
        self.vertical = settings.get("part_vertical", 64.0)
        self.up = "xyz".index(settings.get("up_axis", "z"))
        self.prev = []   # [(id, [world origins])] of the previous frame
        self.cur = []    # the same, this frame
        self.parts = {}  # model-view key -> id, this frame

    def begin_frame(self):
        if self.cur or self.parts:
            self.prev = self.cur
        self.cur = []
        self.parts = {}

    def near_part(self, a, b):
        d = a - b
        along = abs(d[self.up])
        across = math.sqrt(max(0.0, float(d @ d) - along * along))
        return across <= self.horizontal and along <= self.vertical

    def id_for(self, mv, view, no):
        key = tuple(np.round(mv[0:3, :], 4).ravel())
        if key in self.parts:
            return self.parts[key]
        world = mv[0:3, 3]
        if view is not None:
            # The view's rotation and translation undone, not its scale: a game
            # that draws a sky box first (Neverball) makes a view scaled by the
            # sky's size the frame's view, and undoing that scale would shrink
            # the whole frame into one part. Distances stay in eye units.
            rot = view[0:3, 0:3]
            scale = abs(float(np.linalg.det(rot))) ** (1.0 / 3.0)
            if scale > 1e-12 and np.all(np.isfinite(rot)):
                world = (rot / scale).T @ (mv[0:3, 3] - view[0:3, 3])
        return self.assign(key, world, no)

    def id_for_origin(self, origin, no):
        """The entity of a part at `origin`, a position in the world (a
        draw's per-instance origin, group_by = "instance_origin")."""
        world = np.asarray(origin, dtype=np.float64)
        key = ("origin",) + tuple(np.round(world, 4))
        if key in self.parts:
            return self.parts[key]
        return self.assign(key, world, no)

    def assign(self, key, world, no):
        """A part at `world` joins an entity of this frame near it, or takes
        the id of the previous frame's nearest within track_radius, or the
        lowest free one."""
        for ent_id, origins in self.cur:
            if any(self.near_part(world, o) for o in origins):
                origins.append(world)
                self.parts[key] = ent_id
                return ent_id
        taken = {i for i, _ in self.cur}
        best, best_d = None, self.radius
        for ent_id, origins in self.prev:
            if ent_id in taken:
                continue
            dd = min(float(np.linalg.norm(o - world)) for o in origins)
            if dd <= best_d:
                best, best_d = ent_id, dd
        if best is None:
            used = taken | {i for i, _ in self.prev}
            best = next((i for i in range(self.first, self.max_id + 1) if i not in used), None)
            if best is None:
                best = next((i for i in range(self.first, self.max_id + 1) if i not in taken), None)
            if best is None:
                fail_call(no, f"more than {self.max_id - self.first + 1} entities in one frame "
                          "(settings.max_entity_id)")
        self.cur.append((best, [world]))
        self.parts[key] = best
        return best

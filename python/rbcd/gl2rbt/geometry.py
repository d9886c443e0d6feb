"""Each frame's collisionable geometry for rbcd-cpucd --geometry
(docs/gl-capture.md): the objects' eye-space meshes and the frame's
projection, or, for draws under a program (whose projection the capture
never states), their normalized device coordinates with an identity
projection. The map from eye space to clip space is projective, and for
geometry in front of the camera (w > 0) it keeps the contact relation (two
surfaces intersecting, one closed surface inside another), so the ground
truth computed there is the eye space's; what crosses w = 0 is clipped at
w = W_MIN first."""
import numpy as np

from .errors import fail_call

W_MIN = 1e-5
# rbcd-cpucd's bound on a vertex's coordinates and the view's entries
# (docs/limits.md): the converter's geometry keeps it, or the draw is refused.
GEOMETRY_LIMIT = 1e9


def past_limit(verts, tris):
    """Whether a finite vertex a triangle uses lies past GEOMETRY_LIMIT (a
    vertex at infinity, w = 0, is left out with its triangles when written)."""
    if len(tris) == 0:
        return False
    used = verts[np.unique(tris)]
    used = used[np.isfinite(used).all(axis=1)]
    return bool((np.abs(used) > GEOMETRY_LIMIT).any())


def clip_near(clip, tris):
    """Triangles (indices into clip, (n, 4)) cut to w >= W_MIN: (vertices
    (m, 4), triangles (k, 3)). A triangle wholly in front is kept as it is,
    one wholly behind dropped, one across the plane cut to its front part."""
    w = clip[tris, 3]
    front = (w >= W_MIN).all(axis=1)
    keep = tris[front]
    crossing = tris[~front & (w >= W_MIN).any(axis=1)]
    if len(crossing) == 0:
        return clip, keep
    verts, extra = [clip], []
    n = len(clip)
    for tri in crossing:
        poly = []
        for i in range(3):
            a, b = clip[tri[i]], clip[tri[(i + 1) % 3]]
            if a[3] >= W_MIN:
                poly.append(a)
            if (a[3] >= W_MIN) != (b[3] >= W_MIN):
                t = (W_MIN - a[3]) / (b[3] - a[3])
                poly.append(a + t * (b - a))
        for j in range(1, len(poly) - 1):
            extra.append([n, n + j, n + j + 1])
        verts.append(np.array(poly))
        n += len(poly)
    return np.concatenate(verts), np.concatenate([keep, np.array(extra, dtype=keep.dtype).reshape(-1, 3)])


def weld(verts):
    """The vertices as written ("%.9g" each) and, for each vertex, the index
    of its text among them in order of first appearance: vertices whose
    texts are equal are one. Each distinct value (bit for bit) is formatted
    once: GL hands a mesh's corners over once per index."""
    rows = np.ascontiguousarray(verts, dtype=np.float64)
    _, first, inverse = np.unique(rows.view(np.dtype((np.void, rows.dtype.itemsize * 3))).ravel(),
                                  return_index=True, return_inverse=True)
    texts = ["%.9g %.9g %.9g" % (x, y, z) for x, y, z in rows[first].tolist()]
    # Distinct values may print alike: the text decides, at its first appearance.
    by_text = {}
    for u in np.argsort(first, kind="stable").tolist():
        by_text.setdefault(texts[u], len(by_text))
    order = list(by_text)
    text_of_unique = np.fromiter((by_text[t] for t in texts), dtype=np.int64, count=len(texts))
    return order, text_of_unique[inverse.ravel()]


class GeometryOutput:
    """The mixin of Converter that writes the geometry file."""

    def add_geometry(self, no, obj_id, clip, tris, eye, proj):
        """A collisionable draw's surface: eye() its eye-space vertices under
        the fixed-function transform, or None under a program."""
        space = "eye" if eye is not None else "ndc"
        if self.geo_space not in (None, space):
            fail_call(no, "--geometry: a frame's collisionable objects are drawn both with and without "
                      "shaders (their spaces differ)")
        self.geo_space = space
        if eye is not None:
            e = eye()
            verts, kept = e[:, 0:3] / e[:, 3:4], tris
            if not (np.abs(proj) <= GEOMETRY_LIMIT).all():
                fail_call(no, f"--geometry: the projection has an entry past {GEOMETRY_LIMIT:g}, the geometry's "
                          "limit (rbcd-cpucd; docs/limits.md)")
            self.geo_view = proj.copy()   # the objects' projection, not a later overlay's
        else:
            verts, kept = clip_near(clip, tris)
            verts = verts[:, 0:3] / verts[:, 3:4]
            self.geo_view = np.identity(4)
        if past_limit(verts, kept):
            fail_call(no, f"--geometry: a collisionable vertex lies past {GEOMETRY_LIMIT:g} in "
                      f"{'eye space' if eye is not None else 'normalized device coordinates'}, the geometry's limit "
                      "(rbcd-cpucd; docs/limits.md)")
        self.geo_objects.setdefault(obj_id, []).append((verts, kept.copy()))

    def write_geometry_frame(self):
        g = self.geo
        if self.out_frame == 0:
            g.write(f"screen {self.screen[0]} {self.screen[1]}\n")
        g.write(f"frame {self.out_frame}\n")
        if self.geo_view is not None:
            g.write("view " + " ".join(repr(float(x)) for x in self.geo_view.ravel()) + "\n")
        for obj_id in sorted(self.geo_objects):
            parts = self.geo_objects[obj_id]
            verts = np.concatenate([v for v, _ in parts])
            offsets = np.cumsum([0] + [len(v) for v, _ in parts[:-1]])
            tris = np.concatenate([t + o for (_, t), o in zip(parts, offsets)])
            # A vertex no triangle keeps may lie at w = 0 (a vertex shader's
            # way to cull it): at infinity once divided, or past the limit
            # near it. It is not written, nor any triangle that would reach
            # an infinite one (add_geometry refused a used one past the limit).
            finite = np.isfinite(verts).all(axis=1)
            tris = tris[finite[tris].all(axis=1)]
            used = np.zeros(len(verts), dtype=bool)
            used[tris.ravel()] = True
            written = finite & (used | (np.abs(verts) <= GEOMETRY_LIMIT).all(axis=1))
            if not written.all():
                verts, tris = verts[written], (np.cumsum(written) - 1)[tris]
            # GL hands the vertices over once per index (a mesh's corners
            # repeat); written once each, the file is a third of the size. Nine
            # significant digits hold a single-precision vertex exactly and the
            # eye-space position to 1e-9 of its size, far below a pixel.
            order, remap = weld(verts)
            tris = remap[tris]
            # A triangle whose corners weld together covers no area: no
            # fragment of it reaches the unit and it cannot touch anything.
            # A model scaled to a point (OpenArena shrinks some effects to
            # nothing) is all such triangles, and is no surface at all.
            keep = (tris[:, 0] != tris[:, 1]) & (tris[:, 1] != tris[:, 2]) & (tris[:, 0] != tris[:, 2])
            tris = tris[keep]
            if len(tris) == 0 or len(order) < 3:
                continue
            g.write(f"mesh {obj_id} {len(order)} {len(tris)}\n")
            g.write("".join(f"v {k}\n" for k in order))
            g.write("".join(f"t {a} {b} {c}\n" for a, b, c in tris.tolist()))

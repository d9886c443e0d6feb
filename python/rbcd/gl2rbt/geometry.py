"""Each frame's collisionable geometry for rbcd-cpucd --geometry
(docs/gl-capture.md): the objects' eye-space meshes and the frame's projection."""
import numpy as np


class GeometryOutput:
    """The mixin of Converter that writes the geometry file."""

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
            # GL hands the vertices over once per index (a mesh's corners
            # repeat); written once each, the file is a third of the size. Nine
            # significant digits hold a single-precision vertex exactly and the
            # eye-space position to 1e-9 of its size, far below a pixel.
            text = np.char.mod("%.9g", verts)
            keys = [f"{x} {y} {z}" for x, y, z in text]
            index, order = {}, []
            remap = np.empty(len(keys), dtype=np.int64)
            for i, k in enumerate(keys):
                j = index.get(k)
                if j is None:
                    j = index[k] = len(order)
                    order.append(k)
                remap[i] = j
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

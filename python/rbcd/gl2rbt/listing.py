"""--list-draws: every draw of one frame and what it became, and its picture."""
import io
import os
import shutil
import sys

import numpy as np

from ..cli import temporary_folder, to_standard_output, unregister_temporary, write_output
from .errors import ToolError, printable
from .raster import convert

def list_draws(args):
    """Every draw of one frame: call, function, vertices, texture, projection,
    whether it has a model-view of its own (not the frame's view), depth
    writes, screen box, the object it became and the rule that decided; with
    --image, a picture of the frame with each visible draw in its own colour
    and labelled with its index."""
    frame = args.list_draws
    args.frame_range = (frame, frame)
    # An image on standard output ("-" names it, as for the other outputs)
    # has it to itself: the listing goes to standard error.
    if args.image == "-":
        args.image = "/dev/stdout"
    stream = sys.stderr if args.image and to_standard_output([args.image]) else sys.stdout
    out = io.StringIO()   # written whole before the image: a listing that cannot be written leaves no image
    tmp = temporary_folder("rbcd-gl2rbt-list.")
    try:
        args.output = os.path.join(tmp, "list.rbt")
        args.geometry = args.summary = args.depth_out = None
        args.snapshots = set()
        ids_path = os.path.join(tmp, "ids")
        frames, conv = convert(args, listing=True, ids=(ids_path, 0))
        rows = conv.listing
        print(f"frame {frame}: {len(rows)} draws, {len(frames[0]['objects'])} collisionable objects", file=out)
        print("  #   call  function              verts  tex  image     program   data      proj  own-mv depth  "
              "func       box (x0 y0 x1 y1)     object  rule", file=out)
        for r in rows:
            x0, y0, x1, y1 = r["box"]
            obj = "-" if r["object"] is None else str(r["object"])
            print(f"{r['index']:3d} {r['call']:6d}  {printable(r['function'], 20):20s} {r['vertices']:6d} {r['texture']:4d}  "
                  f"{r['texture_image'][:8] or '-':8s}  {r['program'][:8] or '-':8s}  {r['vertex_data'][:8] or '-':8s}  "
                  f"{r['projection'][:5]:5s} {'yes' if r['own_modelview'] else 'no':6s} "
                  f"{'write' if r['depth_write'] else '-':5s}  {r['depth_func'][3:]:9s}  "
                  f"{x0:4d} {y0:4d} {x1:4d} {y1:4d}     {obj:6s}  {printable(r['rule'], 40)}", file=out)
        passes = [(r["call"], r["pass"]) for i, r in enumerate(rows) if r["pass"] and
                  (i == 0 or rows[i - 1]["pass"] != r["pass"])]
        if passes:
            print("passes: " + ", ".join(f"from call {c} {printable(p, 60)!r}" for c, p in passes), file=out)
        if stream is None:   # closed when the program started
            raise ToolError("the listing: write failed: standard output is closed")
        try:
            stream.write(out.getvalue())
            stream.flush()
        except OSError as e:
            raise ToolError(f"the listing: write failed: {printable(e.strerror or e)}")
        if args.image:
            write_draw_image(args.image, ids_path, rows)
        return 0
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
        unregister_temporary(tmp)


def write_draw_image(path, ids_path, rows):
    try:
        from PIL import Image, ImageDraw
    except ImportError:
        raise ToolError("--image needs python3-pil (installed with apitrace)")
    # Memory: the image is built one whole array at a time, each freed as
    # soon as the next is made (8192 x 8192: about 0.45 GB at the peak, the
    # picture in PIL's four bytes a pixel beside its RGB array).
    n = len(rows)
    with open(ids_path, "rb") as f:
        head = f.readline().split()
        w, h = int(head[2]), int(head[3])
        # Each pixel's draw index, the background (0xFFFF) and indices past
        # the listing as n: the palette's last entry.
        idx = np.fromfile(f, dtype="<u2", count=w * h).reshape(h, w)
    idx = idx.astype(np.uint32 if n >= 0xFFFF else np.uint16, copy=False)
    np.minimum(idx, n, out=idx)
    if n > 0xFFFF:
        idx[idx == 0xFFFF] = n
    # Each visible draw's label at the median of its pixels (from counts
    # per column and row: the pixels' coordinates of a draw covering the
    # screen would take 16 bytes each).
    labels = []
    for r in rows:
        mask = idx == r["index"]
        across, down = mask.sum(axis=0), mask.sum(axis=1)
        del mask
        if across.sum() < 20:
            continue
        label = f"{r['index']}" + (f" ={r['object']}" if r["object"] is not None else "")
        labels.append((int(median_of_counts(across)), int(median_of_counts(down)), label, r["object"] is None))
    # Collisionable draws in saturated colours, the rest in greys; the
    # background black.
    pal = np.zeros((max(n, 1) + 1, 3), np.uint8)
    for r in rows:
        k = r["index"]
        if r["object"] is not None:
            hue = (r["object"] * 0.618034) % 1.0
            pal[k] = [int(255 * max(0.0, min(1.0, abs(hue * 6 - 3) - 1))),
                      int(255 * max(0.0, min(1.0, 2 - abs(hue * 6 - 2)))),
                      int(255 * max(0.0, min(1.0, 2 - abs(hue * 6 - 4))))]
            pal[k] = np.maximum(pal[k], 60)
        else:
            g = 50 + (k * 37) % 90
            pal[k] = [g, g, g]
    rgb = pal[idx]
    del idx
    img = Image.fromarray(rgb, "RGB")
    del rgb
    draw = ImageDraw.Draw(img)
    for x, y, label, grey in labels:
        draw.text((x - 6, y - 5), label, fill=(255, 255, 255) if grey else (0, 0, 0))
    buf = io.BytesIO()
    img.save(buf, format="PNG")
    write_output(path, buf.getvalue(), "image")


def median_of_counts(counts):
    """The median (numpy's: the mean of the two middle ones for an even
    number) of the positions counted: counts[i] of position i."""
    c = np.cumsum(counts)
    n = int(c[-1])
    return (np.searchsorted(c, (n - 1) // 2, side="right") + np.searchsorted(c, n // 2, side="right")) / 2


# ---------------------------------------------------------------- the check against Mesa

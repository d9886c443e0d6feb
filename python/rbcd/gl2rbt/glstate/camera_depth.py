"""The camera pass's depth buffers, and the one the converter keeps.

The camera pass can write several depth buffers: the window's, and the
depth attachments of framebuffer objects of the screen's size (a deferred
renderer's geometry pass, an MSAA target resolved into the window). The
converter keeps one, rbcd-gl-raster's, whichever of them a draw writes.
The trace does not depend on it (the unit sees fragments before the depth
test); the check against Mesa (--check-depth) and the --list-draws picture
do, and they are right for a draw only when the kept buffer holds what the
draw's own buffer holds. So each buffer's contents and the kept buffer's
are followed as Depths: a whole clear's value, or contents of their own. A
clear, a draw with depth writes and a whole copy between two of them
(glBlitFramebuffer) set them as GL does; a copy the converter cannot follow
(a part, moved or scaled, from another pass) or new storage gives the
buffer contents of its own. At a draw that tests depth against a buffer
whose contents the kept one does not hold, a whole clear's value is given
back (a clear of the kept buffer: a `C` record); other contents cannot be,
and the kept buffer is wrong until a whole clear: the frames whose last
depth-tested draw comes while it is are not checked, and the report
counts them.

What the buffers hold when the converted frames begin is not known (the
frames before were not followed): all are taken to hold what the kept one
holds."""
import struct

from ..errors import printable


class Depths:
    """What a depth buffer holds: a whole clear's value (`clear`), or
    contents of their own (`clear` None, equal to no other Depths); `how`
    says how they came to be, for messages."""
    __slots__ = ("clear", "how")

    def __init__(self, clear, how):
        self.clear, self.how = clear, how

    def same(self, other):
        return self is other or self.clear is not None and self.clear == other.clear


class CameraDepthCalls:
    """self.depths[key] = Depths of a camera-pass depth buffer (key: "window",
    or a framebuffer's depth attachment as self.s.fbo_depth holds it; one
    absent holds self.depths_at_start); self.kept_depths: the kept buffer's."""

    def camera_depths_start(self):
        """The converted frames begin: every buffer is taken to hold what the
        kept one holds. self.kept_wrong: why the kept buffer does not hold
        what the last depth-tested draw's buffer held (None: it does)."""
        self.depths = {}
        self.depths_at_start = self.kept_depths = Depths(None, "as they were when the converted frames began")
        self.kept_wrong = None

    def bound_depth_attachment(self):
        """The depth attachment of the framebuffer object drawn into, or None
        (the window, or no depth attachment)."""
        return self.s.fbo_depth.get(self.s.draw_fbo) if self.s.draw_fbo else None

    def depth_bits(self):
        """The bits of the bound framebuffer's depth buffer, where they are
        fewer than the trace's: a 16-bit attachment (GL_DEPTH_COMPONENT16,
        or an unsized depth texture of 16-bit pixels, as Mesa stores them);
        the trace's otherwise. --check-depth compares at these."""
        att = self.bound_depth_attachment()
        fmt = self.s.formats.get(att[:2]) if att else None
        if fmt == "GL_DEPTH_COMPONENT16" or fmt == "GL_DEPTH_COMPONENT" and \
                self.s.depth_types.get(att[:2]) == "GL_UNSIGNED_SHORT":
            return min(16, self.args.depth_bits)
        return self.args.depth_bits

    def float_depth(self):
        """Whether the bound framebuffer's depth buffer holds floating-point depths."""
        att = self.bound_depth_attachment()
        return bool(att) and self.s.formats.get(att[:2]) in ("GL_DEPTH_COMPONENT32F", "GL_DEPTH32F_STENCIL8")

    def multisample_depth(self):
        """Why --check-depth cannot compare the bound framebuffer's depth
        buffer: a multisample one, which Mesa's replay reads back one
        sample a pixel of, not the pixel centre's depth the converter
        keeps (None: it can)."""
        att = self.bound_depth_attachment()
        if att is None:
            return None
        tl = self.s.texture_levels.get(att[:2]) if att[0] == "texture" else None
        image = tl.images.get((0, 0)) if tl is not None else None
        samples = image[4] if isinstance(image, tuple) else self.s.multisampled.get(att[:2], 0)
        return f"{self.buffer_name(self.s.draw_fbo)} is multisampled, and Mesa's replay reads back one sample a " \
               "pixel, not the pixel centre's depth" if samples else None

    def depth_key(self, fb):
        return "window" if not fb else self.s.fbo_depth.get(fb)

    def depths_of(self, key):
        return self.depths.get(key, self.depths_at_start)

    def buffer_name(self, fb):
        return "the window's depth buffer" if not fb else f"framebuffer {fb}'s depth buffer"

    def target_name(self, fb):
        return "the window" if not fb else f"framebuffer {fb}"

    def full_screen(self):
        w, h = self.screen
        return (0, 0, w - 1, h - 1)

    def covers_screen(self, rect):
        """Whether an inclusive rectangle (a scissor box's, cut to one pixel
        past the screen) covers all of it."""
        w, h = self.screen
        return rect[0] <= 0 and rect[1] <= 0 and rect[2] >= w - 1 and rect[3] >= h - 1

    def give_back(self, no, held):
        """The kept buffer takes a whole clear's value that `held` is (a `C`
        record); True if it did."""
        if held.clear is None:
            return False
        self.open_frame(no)
        self.emit(b"C" + struct.pack("<Qd4i", no, held.clear, *self.full_screen()))
        self.kept_depths, self.kept_wrong = held, None
        return True

    def depth_tested(self, no, name):
        """A draw into the camera pass's bound framebuffer with the depth
        test on: the kept buffer is right for it if it holds (or can be given
        back) what the draw's buffer holds, wrong (self.kept_wrong says why)
        otherwise; with depth writes, both hold the draw's depths after
        it."""
        fb = self.s.draw_fbo
        key = self.depth_key(fb)
        held = self.depths_of(key)
        if not held.same(self.kept_depths) and not self.give_back(no, held):
            self.kept_wrong = (f"call {no} ({printable(name)}) tests depth against {self.buffer_name(fb)}, whose "
                               f"depths {held.how}, while the one depth buffer the converter keeps for the camera "
                               f"pass held others ({self.kept_depths.how})")
            self.kept_depths = held
        if self.s.depth_mask:
            how = f"were last written by call {no} ({printable(name)}) into {self.target_name(fb)}"
            self.kept_depths = self.depths[key] = Depths(None, how)

    def depth_cleared(self, no, value, rect):
        """A depth clear of the bound camera-pass framebuffer to `value`, of
        `rect` (the scissor's, inclusive), about to be emitted to the kept
        buffer (a part of a buffer whose whole clear's value the kept one
        does not hold is given that value first)."""
        key = self.depth_key(self.s.draw_fbo)
        if self.covers_screen(rect):
            self.kept_depths = self.depths[key] = Depths(value, f"were cleared to {value:g} by call {no}")
            self.kept_wrong = None
            return
        held = self.depths_of(key)
        if held.same(self.kept_depths) or self.give_back(no, held):
            self.kept_depths = self.depths[key] = Depths(None, f"were last cleared in part by call {no}")
        else:
            how = f"were cleared in part by call {no} while the one kept buffer held others"
            self.depths[key] = self.kept_depths = Depths(None, how)
            self.kept_wrong = self.kept_wrong or (f"call {no} cleared a part of {self.buffer_name(self.s.draw_fbo)}, "
                                                  "whose other depths the one kept buffer did not hold")

    def depths_copied(self, src_fb, dst_fb):
        """A whole copy of one camera-pass buffer's depths into another's."""
        self.depths[self.depth_key(dst_fb)] = self.depths_of(self.depth_key(src_fb))

    def depths_replaced(self, key, how):
        """A buffer given contents the converter does not follow (new storage,
        a copy of part of another): a draw that tests against them is
        refused."""
        if self.active and key is not None:
            self.depths[key] = Depths(None, how)

    def depths_renamed(self, old, new):
        """A deleted image that lives on for framebuffers not bound takes a
        name no call can give (FramebufferCalls.detach_deleted)."""
        for key in [k for k in self.depths if isinstance(k, tuple) and k[:2] == old]:
            self.depths[new + key[2:]] = self.depths.pop(key)

    HANDLERS = {}

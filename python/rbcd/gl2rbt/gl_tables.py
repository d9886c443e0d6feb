"""GL's enumerants as the converter reads them, and the calls it may pass over."""

# apitrace's call flags (trace_model.hpp): a call apitrace made up to record
# state (the window's size at MakeCurrent), and a call that ends a frame.
CALL_FLAG_FAKE = 1 << 0
CALL_FLAG_END_FRAME = 1 << 5
# The eleven flags apitrace 11.1 defines (fake to marker pop): a bit above
# them is in no capture apitrace writes.
CALL_FLAGS_APITRACE = (1 << 11) - 1
# The calls apitrace's reader flags as ending a frame (it flags calls by
# their name: the buffer swaps and glFrameTerminatorGREMEDY). The flag on
# any other call (a draw) is in no capture apitrace writes: the capture's
# error, not a frame's end.
END_FRAME_CALLS = frozenset({
    "glXSwapBuffers", "eglSwapBuffers", "eglSwapBuffersWithDamageEXT", "eglSwapBuffersWithDamageKHR",
    "wglSwapBuffers", "wglSwapLayerBuffers", "wglSwapMultipleBuffers", "CGLFlushDrawable",
    "glFrameTerminatorGREMEDY"})
# The argument of each buffer swap naming the window or surface it shows,
# by apitrace's name (window_registry has their parameters; the frame
# terminator and wglSwapMultipleBuffers name none alone).
SWAP_HANDLES = {"glXSwapBuffers": "drawable", "eglSwapBuffers": "surface", "eglSwapBuffersWithDamageEXT": "surface",
                "eglSwapBuffersWithDamageKHR": "surface", "wglSwapBuffers": "hdc", "wglSwapLayerBuffers": "hdc",
                "CGLFlushDrawable": "ctx"}

PRIM_TRIANGLES = {"GL_TRIANGLES", "GL_TRIANGLE_STRIP", "GL_TRIANGLE_FAN", "GL_QUADS", "GL_QUAD_STRIP", "GL_POLYGON"}
PRIM_NO_AREA = {"GL_POINTS", "GL_LINES", "GL_LINE_STRIP", "GL_LINE_LOOP"}
DEPTH_FUNCS = ["GL_NEVER", "GL_LESS", "GL_EQUAL", "GL_LEQUAL", "GL_GREATER", "GL_NOTEQUAL", "GL_GEQUAL", "GL_ALWAYS"]
CULL = {"GL_BACK": 1, "GL_FRONT": 2, "GL_FRONT_AND_BACK": 3}
ARRAY_TYPES = {"GL_FLOAT": "<f4", "GL_DOUBLE": "<f8", "GL_SHORT": "<i2", "GL_INT": "<i4", "GL_BYTE": "i1",
               "GL_UNSIGNED_BYTE": "u1", "GL_UNSIGNED_SHORT": "<u2", "GL_UNSIGNED_INT": "<u4", "GL_HALF_FLOAT": "<f2"}
INDEX_TYPES = {"GL_UNSIGNED_BYTE": "u1", "GL_UNSIGNED_SHORT": "<u2", "GL_UNSIGNED_INT": "<u4"}
MAX_CLIP_PLANES = 8

# Calls that cannot change where a fragment lands or which reach the unit:
# texturing, colour, blending, lighting, fog, materials, queries, the window
# system (the blend factors and draw buffers, which decide whether GL refuses
# a draw, have handlers: glstate/color_outputs.py). Listed in docs/gl-capture.md; anything else that is neither
# emulated nor here is refused.
IGNORED_PREFIXES = (
    "glTex", "glBindTexture", "glGenTextures", "glActiveTexture", "glClientActiveTexture",
    "glCompressedTex", "glCopyTex", "glPixelStore", "glPixelTransfer", "glPixelZoom", "glGenerateMipmap",
    "glColor", "glSecondaryColor", "glNormal", "glFog", "glLight", "glMaterial", "glShadeModel", "glBlend",
    "glAlphaFunc", "glLogicOp", "glClearColor", "glClearStencil", "glClearAccum", "glStencil", "glColorMask",
    "glHint", "glLineWidth", "glPointSize", "glPointParameter", "glLineStipple", "glPolygonStipple",
    "glGet", "glIs", "glFinish", "glFlush", "glReadPixels", "glReadBuffer", "glDrawBuffer", "glPixelMap",
    "glX", "egl", "wgl", "glDebugMessage", "glObjectLabel", "glObjectPtrLabel", "glGetError", "glLockArrays",
    "glUnlockArrays", "glNormalPointer", "glColorPointer", "glTexCoordPointer", "glSecondaryColorPointer",
    "glFogCoordPointer", "glEdgeFlagPointer", "glIndexPointer", "glMultiTexCoord", "glTexCoord", "glFogCoord",
    "glEdgeFlag", "glIndex", "glAccum", "glSampleCoverage", "glGenQueries", "glBeginQuery", "glEndQuery",
    "glDeleteQueries", "glQueryCounter", "glStringMarker", "glFrameTerminator", "glInsertEventMarker",
    "glDebugMessageInsert", "glSampleMask", "glMinSampleShading",
    "glDepthBounds",
    "glRasterPos", "glLoadName", "glPushName", "glPopName", "glInitNames",
    "glGenLists", "glDeleteLists", "glListBase", "glCompileShader", "glShaderSource", "glCreateShader",
    "glCreateProgram", "glAttachShader", "glLinkProgram", "glDeleteShader", "glDetachShader",
    "glBindAttribLocation", "glUniform", "glValidateProgram", "glBindFragDataLocation", "glTexEnv", "glTexGen",
    "glColorTable", "glConvolution", "glHistogram", "glMinmax", "glResetHistogram", "glResetMinmax",
    "glSeparableFilter", "glMap1", "glMap2", "glMapGrid", "memcpy", "glMemcpy", "glBlendEquation",
    # Sampler object names (their bindings and parameters are kept for the
    # vertex shaders that read 2D textures: glstate/textures.py), fences.
    "glGenSamplers", "glCreateSamplers", "glFenceSync",
    "glClientWaitSync", "glWaitSync", "glDeleteSync",
    # Ordering of the GPU's own writes (images, storage buffers) before
    # later reads: what those writes make, the converter reads back from
    # Mesa's replay, which makes the barriers, or refuses.
    "glMemoryBarrier", "glTextureBarrier",
    # Hints that a framebuffer's contents are no longer needed (ES 3 and its
    # EXT form): they change no pixel a later draw or the unit sees.
    "glInvalidateFramebuffer", "glInvalidateSubFramebuffer", "glDiscardFramebuffer",
    # Which colour buffers a framebuffer draws or reads (direct state access),
    # hints that its contents are no longer needed.
    "glNamedFramebufferDrawBuffer", "glNamedFramebufferReadBuffer", "glInvalidateNamedFramebuffer",
)
# Direct state access on textures that cannot make a 2D texture's image
# (synchronisation; 1D and 3D images, GL_INVALID_OPERATION on a 2D texture);
# every other unhandled glTexture* call is refused, not passed over.
TEXTURE_IGNORED = {"glTextureBarrier", "glTextureSubImage1D", "glTextureSubImage3D", "glCompressedTextureSubImage1D",
                   "glCompressedTextureSubImage3D"}
# Passed-over calls that may change a texture's image or sampling (one of a
# target other than 2D: read back from Mesa's replay when a vertex shader
# reads it, again after such a call).
TEXTURE_CHANGING = ("glTexImage", "glTexSubImage", "glTexStorage", "glTexParameter", "glCompressedTex", "glCopyTex",
                    "glGenerateMipmap", "glTexture", "glGenerateTextureMipmap", "glCompressedTexture",
                    "glCopyTexture", "glTexBuffer")
# The compatibility profile's calls (by base name): in a core profile they
# are GL_INVALID_OPERATION in Mesa and change nothing.
COMPAT_ONLY = {
    "glTexEnvf", "glTexEnvi", "glTexEnvfv", "glTexEnviv",
    "glMatrixMode", "glLoadIdentity", "glLoadMatrixf", "glLoadMatrixd", "glLoadTransposeMatrixf",
    "glLoadTransposeMatrixd", "glMultMatrixf", "glMultMatrixd", "glMultTransposeMatrixf", "glMultTransposeMatrixd",
    "glTranslatef", "glTranslated", "glRotatef", "glRotated", "glScalef", "glScaled", "glPushMatrix", "glPopMatrix",
    "glOrtho", "glFrustum", "glClipPlane", "glVertexPointer", "glEnableClientState", "glDisableClientState",
    "glInterleavedArrays", "glBegin", "glEnd", "glRectf", "glRectd", "glRecti", "glRects", "glRectfv", "glRectdv",
    "glRectiv", "glRectsv", "glRenderMode", "glDrawPixels", "glCopyPixels", "glBitmap", "glPrimitiveRestartNV",
    "glPrimitiveRestartIndexNV", "glNewList", "glEndList", "glCallList", "glCallLists", "glArrayElement", "glEvalMesh1",
    "glEvalMesh2", "glEvalCoord1f", "glEvalCoord2f", "glEvalPoint1", "glEvalPoint2", "glPushAttrib", "glPopAttrib",
    "glPushClientAttrib", "glPopClientAttrib",
}

# Capabilities of glEnable/glDisable whose effect on the unit's input is nil or
# emulated; others are refused when enabled.
CAPS_IGNORED = {
    "GL_TEXTURE_1D", "GL_TEXTURE_2D", "GL_TEXTURE_3D", "GL_TEXTURE_CUBE_MAP", "GL_TEXTURE_RECTANGLE",
    "GL_BLEND", "GL_ALPHA_TEST", "GL_STENCIL_TEST", "GL_FOG", "GL_LIGHTING", "GL_COLOR_MATERIAL",
    "GL_NORMALIZE", "GL_RESCALE_NORMAL", "GL_DITHER", "GL_MULTISAMPLE", "GL_LINE_SMOOTH", "GL_POINT_SMOOTH",
    "GL_POLYGON_SMOOTH", "GL_LINE_STIPPLE", "GL_POLYGON_STIPPLE", "GL_TEXTURE_GEN_S", "GL_TEXTURE_GEN_T",
    "GL_TEXTURE_GEN_R", "GL_TEXTURE_GEN_Q", "GL_COLOR_LOGIC_OP", "GL_SAMPLE_ALPHA_TO_COVERAGE",
    "GL_SAMPLE_COVERAGE", "GL_SAMPLE_MASK", "GL_SAMPLE_SHADING", "GL_POLYGON_OFFSET_LINE", "GL_POLYGON_OFFSET_POINT", "GL_FRAMEBUFFER_SRGB",
    "GL_DEBUG_OUTPUT", "GL_DEBUG_OUTPUT_SYNCHRONOUS", "GL_VERTEX_PROGRAM_POINT_SIZE", "GL_POINT_SPRITE",
    "GL_COLOR_SUM", "GL_AUTO_NORMAL", "GL_INDEX_LOGIC_OP", "GL_PROGRAM_POINT_SIZE",
} | {f"GL_LIGHT{i}" for i in range(8)}

# The largest buffer object a capture may declare (bytes), and the data all
# its buffers may hold at once (written bytes: declared storage costs nothing).
MAX_BUFFER_BYTES = 1 << 30
MAX_BUFFER_BYTES_IN_ALL = 2 << 30


# Extension entry points Mesa 22.3 answers with a stub that does nothing, in
# desktop and ES contexts alike (its llvmpipe exposes no EXT_instanced_arrays,
# ANGLE_instanced_arrays or NV_instanced_arrays; the ARB form sets the
# divisor): a capture's call of one changes nothing, as there. Measured by
# testbench/gl/test_gl2rbt_draw_outcomes.py against Mesa itself.
MESA_NO_OPS = {"glVertexAttribDivisorEXT", "glVertexAttribDivisorANGLE", "glVertexAttribDivisorNV",
               "glDepthBoundsEXT"}   # (llvmpipe has no EXT_depth_bounds_test)
# Capabilities of extensions Mesa 22.3's llvmpipe does not have: glEnable of
# them is GL_INVALID_ENUM, nothing changes.
CAPS_MESA_LACKS = {"GL_DEPTH_BOUNDS_TEST_EXT"}
# Extension forms of core calls that Mesa 22.3 keeps to the compatibility
# profile (EXT_polygon_offset): in a core profile they change nothing.
COMPAT_ONLY_FORMS = {"glPolygonOffsetEXT"}
# Extension forms of core calls Mesa 22.3 exposes in OpenGL ES alone
# (EXT_texture_storage): GL_INVALID_OPERATION in desktop contexts.
ES_ONLY_FORMS = {"glTexStorage2DEXT"}


def base_name(name):
    """A GL function's name without its extension suffix: the ARB, EXT, KHR
    and OES forms behave as the core function."""
    return name[:-3] if name.endswith(("ARB", "EXT", "KHR", "OES")) else name

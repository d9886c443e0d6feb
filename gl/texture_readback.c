/* Preloaded into glretrace by `rbcd-gl2rbt` when a vertex shader reads a 2D
 * texture the GPU renders (docs/gl-capture.md, "Textures a vertex shader
 * reads"): Mesa replays the whole capture, and this library reads the
 * textures back at the draws the converter asks for.
 *
 * glretrace --markers inserts, before each GL call it replays, a debug
 * message that begins with the call's number (glDebugMessageInsert, looked
 * up through glXGetProcAddressARB, which glretrace looks up with dlsym).
 * This library wraps that lookup and so sees every call number. Requests
 * come on the FIFO $RBCD_TEXTURE_FIFOS/requests, one text line each, "CALL
 * UNIT[:TARGET]...", in increasing call order; when the replay reaches CALL,
 * the texture bound at each UNIT's TARGET (GL_TEXTURE_2D when none is given;
 * 1D, 3D, cube map, array, rectangle and multisample ones too; a
 * UNIT of IMAGE_UNIT_BASE and more names image unit UNIT - IMAGE_UNIT_BASE,
 * whose texture is read as if bound at unit 0's TARGET) is
 * read back with its sampling parameters, every level with an image, in a
 * format and type that give its values back exactly when uploaded again
 * (desktop GL: glGetTexImage; OpenGL ES, which has none: glReadPixels from
 * a framebuffer object each of the level's images is attached to in turn,
 * which takes the formats a framebuffer can hold, depth too); the answer
 * goes to
 * $RBCD_TEXTURE_FIFOS/replies:
 *
 *   "RBTX", u32 units; per unit: u32 unit, target, i32 internal format, u32
 *   parameters, each u32 name and 4 f32 values (a multisample texture's
 *   first GL_TEXTURE_SAMPLES: samples, fixed locations, layers; its level 0
 *   holds layers x samples images, read by a compute shader of ours
 *   without the texture's swizzle, as four floats, the depth in the first,
 *   or four 32-bit integers); u32
 *   levels; per level: u32
 *   level, width, height, depth (a cube map's 6 faces, in GL's order), format,
 *   type, u64 bytes, the bytes (rows from the bottom, packed: alignment 1)
 *   or "RBTE", u32 length, a message.
 *
 * The pixel pack state, the active unit, unit 0's binding an image's read
 * took and any pixel pack buffer are put back as the replay had them. When the requests end (the converter closed
 * its end), the replay has nothing more to give and the process exits. */
#define _GNU_SOURCE
#include <dlfcn.h>
#include <errno.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include <fcntl.h>

#include <GL/gl.h>
#include <GL/glext.h>

#include "next_dlsym.h"

typedef void *(*GetProc)(const char *);
typedef void (*DebugMessageInsert)(GLenum, GLenum, GLuint, GLenum, GLsizei, const GLchar *);
typedef void *(*EglGetProc)(const char *);

#define MAX_UNITS 192
#define MAX_LEVELS 15
#define MAX_REPLY_BYTES (1ull << 30)
#define IMAGE_UNIT_BASE 65536   /* (vertex_textures.IMAGE_UNIT_BASE) */

static GetProc real_get_proc;   /* glXGetProcAddressARB or eglGetProcAddress, whichever glretrace looks up */
static DebugMessageInsert real_insert, real_insert_khr;
static int requests = -1, replies = -1;
static long long want = -1;          /* the call asked for; -1: read the next request */
static long want_units[MAX_UNITS];
static int want_count;
static GLenum want_targets[MAX_UNITS];

static struct {
    void (*get_integerv)(GLenum, GLint *);
    void (*active_texture)(GLenum);
    void (*pixel_storei)(GLenum, GLint);
    void (*bind_buffer)(GLenum, GLuint);
    void (*get_tex_level_parameteriv)(GLenum, GLint, GLenum, GLint *);
    void (*get_tex_image)(GLenum, GLint, GLenum, GLenum, void *);
    void (*get_tex_parameterfv)(GLenum, GLenum, GLfloat *);
    void (*tex_parameteri)(GLenum, GLenum, GLint);
    GLenum (*get_error)(void);
    const GLubyte *(*get_string)(GLenum);
    void (*gen_framebuffers)(GLsizei, GLuint *);
    void (*delete_framebuffers)(GLsizei, const GLuint *);
    void (*bind_framebuffer)(GLenum, GLuint);
    void (*framebuffer_texture_2d)(GLenum, GLenum, GLenum, GLuint, GLint);
    void (*framebuffer_texture_layer)(GLenum, GLenum, GLuint, GLint, GLint);
    GLenum (*check_framebuffer_status)(GLenum);
    void (*read_pixels)(GLint, GLint, GLsizei, GLsizei, GLenum, GLenum, void *);
    void (*bind_texture)(GLenum, GLuint);
    void (*get_integeri_v)(GLenum, GLuint, GLint *);
    /* A multisample texture's read (read_multisample). */
    void (*get_integer64i_v)(GLenum, GLuint, GLint64 *);
    GLuint (*create_shader)(GLenum);
    void (*shader_source)(GLuint, GLsizei, const GLchar *const *, const GLint *);
    void (*compile_shader)(GLuint);
    GLuint (*create_program)(void);
    void (*attach_shader)(GLuint, GLuint);
    void (*link_program)(GLuint);
    void (*get_programiv)(GLuint, GLenum, GLint *);
    void (*use_program)(GLuint);
    GLint (*get_uniform_location)(GLuint, const GLchar *);
    void (*uniform1i)(GLint, GLint);
    void (*gen_buffers)(GLsizei, GLuint *);
    void (*buffer_data)(GLenum, GLsizeiptr, const void *, GLenum);
    void (*bind_buffer_base)(GLenum, GLuint, GLuint);
    void (*bind_buffer_range)(GLenum, GLuint, GLuint, GLintptr, GLsizeiptr);
    void (*dispatch_compute)(GLuint, GLuint, GLuint);
    void (*memory_barrier)(GLbitfield);
    void *(*map_buffer_range)(GLenum, GLintptr, GLsizeiptr, GLbitfield);
    GLboolean (*unmap_buffer)(GLenum);
    void (*delete_buffers)(GLsizei, const GLuint *);
    void (*delete_program)(GLuint);
    void (*delete_shader)(GLuint);
} gl;
static int es;   /* the replay's context is OpenGL ES's */

static void die(void)
{
    _exit(0);   /* nothing more is asked for: the replay stops here */
}

static void put(const void *p, size_t n)
{
    const char *c = p;
    while (n) {
        ssize_t k = write(replies, c, n);
        if (k < 0 && errno == EINTR)
            continue;
        if (k <= 0)
            die();
        c += k;
        n -= (size_t)k;
    }
}

static void put_u32(uint32_t v) { put(&v, 4); }

static void refuse(const char *message)
{
    put("RBTE", 4);
    put_u32((uint32_t)strlen(message));
    put(message, strlen(message));
}

/* The next request: "CALL UNIT[:TARGET]..." (at most MAX_UNITS; a unit
 * without a target is GL_TEXTURE_2D's). */
static void next_request(void)
{
    char line[8192];
    size_t n = 0;
    for (;;) {
        char ch;
        ssize_t k = read(requests, &ch, 1);
        if (k < 0 && errno == EINTR)
            continue;
        if (k <= 0)
            die();
        if (ch == '\n')
            break;
        if (n + 1 < sizeof line)
            line[n++] = ch;
    }
    line[n] = 0;
    char *p = line, *end;
    want = strtoll(p, &end, 10);
    want_count = 0;
    for (p = end; want_count < MAX_UNITS; p = end) {
        long u = strtol(p, &end, 10);
        if (end == p)
            break;
        want_units[want_count] = u;
        want_targets[want_count] = GL_TEXTURE_2D;
        if (*end == ':') {
            p = end + 1;
            want_targets[want_count] = (GLenum)strtoul(p, &end, 10);
        }
        want_count++;
    }
}

/* What one unit's texture is read back as. */
struct Texture {
    GLenum target, query;        /* query: the target its levels are asked at (a cube map's first face) */
    GLint internal;
    GLenum format, type;
    GLint levels, size[MAX_LEVELS][3];   /* width, height, depth (a cube map's 6 faces) */
    GLint samples, fixed, layers;        /* a multisample texture's; its level 0 holds layers x samples images */
};

static int multisample(GLenum t) { return t == GL_TEXTURE_2D_MULTISAMPLE || t == GL_TEXTURE_2D_MULTISAMPLE_ARRAY; }

static int known_target(GLenum t)
{
    return t == GL_TEXTURE_2D || t == GL_TEXTURE_3D || t == GL_TEXTURE_2D_ARRAY || t == GL_TEXTURE_CUBE_MAP ||
           t == GL_TEXTURE_CUBE_MAP_ARRAY || t == GL_TEXTURE_1D || t == GL_TEXTURE_1D_ARRAY ||
           t == GL_TEXTURE_RECTANGLE || multisample(t);
}

/* How a level reads back exactly: its values, uploaded again into the
 * same internal format with this format and type, are the level's. */
static void readback_format(struct Texture *t)
{
    GLint depth = 0, stencil = 0, red_type = 0;
    gl.get_tex_level_parameteriv(t->query, 0, GL_TEXTURE_DEPTH_SIZE, &depth);
    gl.get_tex_level_parameteriv(t->query, 0, GL_TEXTURE_STENCIL_SIZE, &stencil);
    gl.get_tex_level_parameteriv(t->query, 0, depth ? GL_TEXTURE_DEPTH_TYPE : GL_TEXTURE_RED_TYPE, &red_type);
    if (depth && stencil) {
        t->format = GL_DEPTH_STENCIL;
        t->type = t->internal == GL_DEPTH32F_STENCIL8 ? GL_FLOAT_32_UNSIGNED_INT_24_8_REV : GL_UNSIGNED_INT_24_8;
    } else if (depth) {
        t->format = GL_DEPTH_COMPONENT;
        t->type = red_type == GL_FLOAT ? GL_FLOAT : GL_UNSIGNED_INT;
    } else if (red_type == GL_INT || red_type == GL_UNSIGNED_INT) {
        t->format = GL_RGBA_INTEGER;
        t->type = red_type == GL_INT ? GL_INT : GL_UNSIGNED_INT;
    } else if (es && red_type == GL_UNSIGNED_NORMALIZED) {
        static const GLenum sizes[4] = {GL_TEXTURE_RED_SIZE, GL_TEXTURE_GREEN_SIZE, GL_TEXTURE_BLUE_SIZE,
                                        GL_TEXTURE_ALPHA_SIZE};
        GLint widest = 0;
        for (int i = 0; i < 4; i++) {
            GLint bits = 0;
            gl.get_tex_level_parameteriv(t->query, 0, sizes[i], &bits);
            widest = bits > widest ? bits : widest;
        }
        /* RGBA bytes, which glReadPixels always takes: uploaded again into
         * the texture's own format, a channel of 8 bits or fewer gets its
         * value back. RGB565 (whose OpenGL ES upload table takes no RGBA
         * bytes) and RGB10_A2 in their packed types, the implementation's
         * read format for them. */
        t->format = GL_RGBA;
        t->type = widest <= 8 ? GL_UNSIGNED_BYTE : 0;   /* 0: none gives its values back (read_level_es) */
        if (t->internal == GL_RGB565)
            t->format = GL_RGB, t->type = GL_UNSIGNED_SHORT_5_6_5;
        else if (t->internal == GL_RGB10_A2)
            t->type = GL_UNSIGNED_INT_2_10_10_10_REV;
    } else {
        t->format = GL_RGBA;   /* float32 holds every normalized and float value, rounded back exactly */
        t->type = GL_FLOAT;
    }
}

static size_t pixel_bytes(GLenum format, GLenum type)
{
    if (format == GL_DEPTH_STENCIL)
        return type == GL_UNSIGNED_INT_24_8 ? 4 : 8;
    if (type == GL_UNSIGNED_BYTE || type == GL_UNSIGNED_INT_2_10_10_10_REV)
        return 4;
    if (type == GL_UNSIGNED_SHORT_5_6_5)
        return 2;
    return format == GL_DEPTH_COMPONENT ? 4 : 16;
}

static uint64_t level_bytes(const struct Texture *t, int i)
{
    return (uint64_t)t->size[i][0] * (uint64_t)t->size[i][1] * (uint64_t)t->size[i][2] *
           pixel_bytes(t->format, t->type);
}

/* The texture bound at the active unit's target, described. */
static void describe(struct Texture *t, GLenum target)
{
    memset(t, 0, sizeof *t);
    t->target = target;
    t->query = target == GL_TEXTURE_CUBE_MAP ? GL_TEXTURE_CUBE_MAP_POSITIVE_X : target;
    gl.get_tex_level_parameteriv(t->query, 0, GL_TEXTURE_INTERNAL_FORMAT, &t->internal);
    readback_format(t);
    if (multisample(target)) {
        /* Each sample of each layer read as an image of its own, as four
         * floats (depth in the first) or four 32-bit integers. */
        GLint w = 0, h = 0, d = 0;
        gl.get_tex_level_parameteriv(target, 0, GL_TEXTURE_WIDTH, &w);
        gl.get_tex_level_parameteriv(target, 0, GL_TEXTURE_HEIGHT, &h);
        gl.get_tex_level_parameteriv(target, 0, GL_TEXTURE_DEPTH, &d);
        gl.get_tex_level_parameteriv(target, 0, GL_TEXTURE_SAMPLES, &t->samples);
        gl.get_tex_level_parameteriv(target, 0, GL_TEXTURE_FIXED_SAMPLE_LOCATIONS, &t->fixed);
        if (t->format != GL_RGBA_INTEGER) {
            t->format = GL_RGBA;
            t->type = GL_FLOAT;
        }
        t->layers = d > 0 ? d : 1;
        if (w > 0 && h > 0 && t->samples > 0) {
            t->size[0][0] = w, t->size[0][1] = h, t->size[0][2] = t->layers * t->samples;
            t->levels = 1;
        }
        return;
    }
    for (GLint level = 0; level < MAX_LEVELS; level++) {
        GLint w = 0, h = 0, d = 0;
        gl.get_tex_level_parameteriv(t->query, level, GL_TEXTURE_WIDTH, &w);
        gl.get_tex_level_parameteriv(t->query, level, GL_TEXTURE_HEIGHT, &h);
        gl.get_tex_level_parameteriv(t->query, level, GL_TEXTURE_DEPTH, &d);
        if (target == GL_TEXTURE_CUBE_MAP)
            d = 6;
        t->size[level][0] = w > 0 ? w : 0;
        t->size[level][1] = h > 0 ? h : 0;
        t->size[level][2] = d > 0 ? d : 1;
        t->levels += w > 0;
    }
}

/* The binding of each target a texture is read back at. */
static GLenum binding_of(GLenum target)
{
    switch (target) {
    case GL_TEXTURE_1D: return GL_TEXTURE_BINDING_1D;
    case GL_TEXTURE_3D: return GL_TEXTURE_BINDING_3D;
    case GL_TEXTURE_2D_ARRAY: return GL_TEXTURE_BINDING_2D_ARRAY;
    case GL_TEXTURE_CUBE_MAP: return GL_TEXTURE_BINDING_CUBE_MAP;
    case GL_TEXTURE_CUBE_MAP_ARRAY: return GL_TEXTURE_BINDING_CUBE_MAP_ARRAY;
    case GL_TEXTURE_1D_ARRAY: return GL_TEXTURE_BINDING_1D_ARRAY;
    case GL_TEXTURE_RECTANGLE: return GL_TEXTURE_BINDING_RECTANGLE;
    case GL_TEXTURE_2D_MULTISAMPLE: return GL_TEXTURE_BINDING_2D_MULTISAMPLE;
    case GL_TEXTURE_2D_MULTISAMPLE_ARRAY: return GL_TEXTURE_BINDING_2D_MULTISAMPLE_ARRAY;
    default: return GL_TEXTURE_BINDING_2D;
    }
}

/* A level as OpenGL ES reads it: each of its images (a 2D texture's one, a
 * cube map's 6 faces, a 3D texture's slices, an array's layers, a cube map
 * array's layer-faces) attached in turn to a framebuffer object of our own
 * and read with glReadPixels, colour at GL_COLOR_ATTACHMENT0, depth (and
 * stencil) at its own attachment, which NV_read_depth and
 * NV_read_depth_stencil read in the texture's own type; the replay's
 * framebuffer bindings put back. 0 if it cannot be (a colour format no
 * type gives back, one a framebuffer cannot hold). */
static int read_level_es(const struct Texture *t, GLint level, void *pixels)
{
    const GLint w = t->size[level][0], h = t->size[level][1], images = t->size[level][2];
    if (!t->type || !gl.framebuffer_texture_layer)
        return 0;
    const GLenum attachment = t->format == GL_DEPTH_STENCIL     ? GL_DEPTH_STENCIL_ATTACHMENT
                              : t->format == GL_DEPTH_COMPONENT ? GL_DEPTH_ATTACHMENT
                                                                : GL_COLOR_ATTACHMENT0;
    const size_t image = level_bytes(t, level) / (size_t)images;
    GLint tex = 0, draw = 0, read = 0;
    gl.get_integerv(binding_of(t->target), &tex);
    gl.get_integerv(GL_DRAW_FRAMEBUFFER_BINDING, &draw);
    gl.get_integerv(GL_READ_FRAMEBUFFER_BINDING, &read);
    GLuint fb = 0;
    gl.gen_framebuffers(1, &fb);
    gl.bind_framebuffer(GL_FRAMEBUFFER, fb);
    int ok = 1;
    for (GLint i = 0; i < images && ok; i++) {
        if (t->target == GL_TEXTURE_2D)
            gl.framebuffer_texture_2d(GL_FRAMEBUFFER, attachment, GL_TEXTURE_2D, (GLuint)tex, level);
        else if (t->target == GL_TEXTURE_CUBE_MAP)
            gl.framebuffer_texture_2d(GL_FRAMEBUFFER, attachment, GL_TEXTURE_CUBE_MAP_POSITIVE_X + (GLenum)i,
                                      (GLuint)tex, level);
        else
            gl.framebuffer_texture_layer(GL_FRAMEBUFFER, attachment, (GLuint)tex, level, i);
        ok = gl.check_framebuffer_status(GL_FRAMEBUFFER) == GL_FRAMEBUFFER_COMPLETE;
        if (ok)
            gl.read_pixels(0, 0, w, h, t->format, t->type, (char *)pixels + (size_t)i * image);
        ok = ok && gl.get_error() == GL_NO_ERROR;
        gl.framebuffer_texture_2d(GL_FRAMEBUFFER, attachment, GL_TEXTURE_2D, 0, 0);
    }
    gl.bind_framebuffer(GL_DRAW_FRAMEBUFFER, (GLuint)draw);
    gl.bind_framebuffer(GL_READ_FRAMEBUFFER, (GLuint)read);
    gl.delete_framebuffers(1, &fb);
    return ok;
}

/* A multisample texture bound at `unit`, read by a compute shader of our
 * own (texelFetch of each sample into a shader storage buffer): image
 * (layer * samples + sample) of level 0's, rows from the bottom. The
 * program in use and shader storage binding 0 are put back as the replay
 * had them. 0 if it cannot be read, -1 if the program in use is deleted
 * (in use, it lives on; once another is used, it is gone). */
static int read_multisample(const struct Texture *t, int unit, void *pixels)
{
    const int array = t->target == GL_TEXTURE_2D_MULTISAMPLE_ARRAY;
    const char *kind = t->format != GL_RGBA_INTEGER ? "" : t->type == GL_INT ? "i" : "u";
    char source[1024];
    snprintf(source, sizeof source,
             "#version %s\n"
             "layout(local_size_x = 1) in;\n"
             "uniform highp %ssampler2DMS%s t;\n"
             "uniform int samples;\n"
             "layout(std430, binding = 0) writeonly buffer Out { highp %svec4 v[]; };\n"
             "void main() {\n"
             "    ivec3 p = ivec3(gl_GlobalInvocationID);\n"
             "    int w = int(gl_NumWorkGroups.x), h = int(gl_NumWorkGroups.y);\n"
             "    for (int s = 0; s < samples; s++)\n"
             "        v[((p.z * samples + s) * h + p.y) * w + p.x] = texelFetch(t, %s, s);\n"
             "}\n",
             es ? (array ? "320 es" : "310 es") : "430", kind, array ? "Array" : "", kind, array ? "p" : "p.xy");
    GLint program = 0, generic = 0, bound = 0, deleted = 0;
    GLint64 start = 0, size = 0;
    gl.get_integerv(GL_CURRENT_PROGRAM, &program);
    if (program)
        gl.get_programiv((GLuint)program, GL_DELETE_STATUS, &deleted);
    if (deleted)
        return -1;   /* switching to ours would free it: the replay's draws need it */
    gl.get_integerv(GL_SHADER_STORAGE_BUFFER_BINDING, &generic);
    gl.get_integeri_v(GL_SHADER_STORAGE_BUFFER_BINDING, 0, &bound);
    gl.get_integer64i_v(GL_SHADER_STORAGE_BUFFER_START, 0, &start);
    gl.get_integer64i_v(GL_SHADER_STORAGE_BUFFER_SIZE, 0, &size);
    const char *text = source;
    GLuint shader = gl.create_shader(GL_COMPUTE_SHADER), prog = gl.create_program(), buf = 0;
    gl.shader_source(shader, 1, &text, NULL);
    gl.compile_shader(shader);
    gl.attach_shader(prog, shader);
    gl.link_program(prog);
    GLint linked = 0;
    gl.get_programiv(prog, GL_LINK_STATUS, &linked);
    const uint64_t n = level_bytes(t, 0);
    /* Read without the texture's swizzle (texelFetch applies it): the
     * converter gives its copy the swizzle again, and a depth format's
     * first component must be the depth. */
    static const GLenum swizzle[4] = {GL_TEXTURE_SWIZZLE_R, GL_TEXTURE_SWIZZLE_G, GL_TEXTURE_SWIZZLE_B,
                                      GL_TEXTURE_SWIZZLE_A};
    GLfloat saved[4][4] = {{0}};
    for (int i = 0; i < 4; i++) {
        gl.get_tex_parameterfv(t->target, swizzle[i], saved[i]);
        gl.tex_parameteri(t->target, swizzle[i], (GLint)(GL_RED + (GLenum)i));
    }
    int ok = 0;
    if (linked) {
        gl.use_program(prog);
        gl.uniform1i(gl.get_uniform_location(prog, "t"), unit);
        gl.uniform1i(gl.get_uniform_location(prog, "samples"), t->samples);
        gl.gen_buffers(1, &buf);
        gl.bind_buffer(GL_SHADER_STORAGE_BUFFER, buf);
        gl.buffer_data(GL_SHADER_STORAGE_BUFFER, (GLsizeiptr)n, NULL, GL_STREAM_READ);
        gl.bind_buffer_base(GL_SHADER_STORAGE_BUFFER, 0, buf);
        while (gl.get_error() != GL_NO_ERROR)
            ;
        gl.dispatch_compute((GLuint)t->size[0][0], (GLuint)t->size[0][1], (GLuint)t->layers);
        gl.memory_barrier(GL_BUFFER_UPDATE_BARRIER_BIT | GL_SHADER_STORAGE_BARRIER_BIT);
        void *mapped = gl.map_buffer_range(GL_SHADER_STORAGE_BUFFER, 0, (GLsizeiptr)n, GL_MAP_READ_BIT);
        if (mapped) {
            memcpy(pixels, mapped, n);
            gl.unmap_buffer(GL_SHADER_STORAGE_BUFFER);
        }
        ok = mapped && gl.get_error() == GL_NO_ERROR;
    }
    for (int i = 0; i < 4; i++)
        gl.tex_parameteri(t->target, swizzle[i], (GLint)saved[i][0]);
    gl.use_program((GLuint)program);
    if (size > 0)
        gl.bind_buffer_range(GL_SHADER_STORAGE_BUFFER, 0, (GLuint)bound, (GLintptr)start, (GLsizeiptr)size);
    else
        gl.bind_buffer_base(GL_SHADER_STORAGE_BUFFER, 0, (GLuint)bound);
    gl.bind_buffer(GL_SHADER_STORAGE_BUFFER, (GLuint)generic);
    if (buf)
        gl.delete_buffers(1, &buf);
    gl.delete_program(prog);
    gl.delete_shader(shader);
    return ok;
}

/* One level's pixels into `pixels` (level_bytes of them); 0 if they cannot
 * be read. */
static int read_level(const struct Texture *t, GLint level, void *pixels)
{
    while (gl.get_error() != GL_NO_ERROR)
        ;
    if (es)
        return read_level_es(t, level, pixels);
    if (t->target == GL_TEXTURE_CUBE_MAP) {
        const size_t face = level_bytes(t, level) / 6;
        for (GLenum f = 0; f < 6; f++)
            gl.get_tex_image(GL_TEXTURE_CUBE_MAP_POSITIVE_X + f, level, t->format, t->type, (char *)pixels + f * face);
    } else {
        gl.get_tex_image(t->target, level, t->format, t->type, pixels);
    }
    return gl.get_error() == GL_NO_ERROR;   /* (a format glGetTexImage refuses: not zeros in its place) */
}

/* The sampling parameters sent with a texture (those the context has). */
static const GLenum parameters[] = {
    GL_TEXTURE_MIN_FILTER, GL_TEXTURE_MAG_FILTER, GL_TEXTURE_WRAP_S, GL_TEXTURE_WRAP_T, GL_TEXTURE_WRAP_R,
    GL_TEXTURE_BASE_LEVEL, GL_TEXTURE_MAX_LEVEL, GL_TEXTURE_MIN_LOD, GL_TEXTURE_MAX_LOD, GL_TEXTURE_LOD_BIAS,
    GL_TEXTURE_COMPARE_MODE, GL_TEXTURE_COMPARE_FUNC, GL_TEXTURE_SWIZZLE_R, GL_TEXTURE_SWIZZLE_G,
    GL_TEXTURE_SWIZZLE_B, GL_TEXTURE_SWIZZLE_A, GL_TEXTURE_BORDER_COLOR, GL_DEPTH_STENCIL_TEXTURE_MODE,
    GL_TEXTURE_IMMUTABLE_LEVELS};   /* (a query: the converter makes an immutable texture immutable) */
#define NPARAMETERS (sizeof parameters / sizeof parameters[0])

/* Makes request k's texture the active unit's: its texture unit, or, for
 * an image unit, unit 0 with the image's texture bound at the target (the
 * binding it replaces into *saved, for unselect). 0 if the image's texture
 * is not of the target asked for. */
static int select_unit(int k, GLint *saved)
{
    if (want_units[k] < IMAGE_UNIT_BASE) {
        gl.active_texture(GL_TEXTURE0 + (GLenum)want_units[k]);
        return 1;
    }
    GLint tex = 0;
    gl.get_integeri_v(GL_IMAGE_BINDING_NAME, (GLuint)(want_units[k] - IMAGE_UNIT_BASE), &tex);
    gl.active_texture(GL_TEXTURE0);
    gl.get_integerv(binding_of(want_targets[k]), saved);
    while (gl.get_error() != GL_NO_ERROR)
        ;
    gl.bind_texture(want_targets[k], (GLuint)tex);
    return gl.get_error() == GL_NO_ERROR;
}

/* The texture unit request k's texture is read at (select_unit's). */
static int unit_of(int k) { return want_units[k] < IMAGE_UNIT_BASE ? (int)want_units[k] : 0; }

static void unselect_unit(int k, GLint saved)
{
    if (want_units[k] >= IMAGE_UNIT_BASE) {
        gl.active_texture(GL_TEXTURE0);
        gl.bind_texture(want_targets[k], (GLuint)saved);
    }
}

static void answer(void)
{
    /* OpenGL ES has the last four alone. */
    static const GLenum pack[] = {GL_PACK_SWAP_BYTES, GL_PACK_LSB_FIRST, GL_PACK_IMAGE_HEIGHT, GL_PACK_SKIP_IMAGES,
                                  GL_PACK_ROW_LENGTH, GL_PACK_SKIP_ROWS, GL_PACK_SKIP_PIXELS, GL_PACK_ALIGNMENT};
    GLint saved[8] = {0}, active = GL_TEXTURE0, pack_buffer = 0;
    const size_t first = es ? 4 : 0, npack = sizeof pack / sizeof pack[0];
    gl.get_integerv(GL_ACTIVE_TEXTURE, &active);
    gl.get_integerv(GL_PIXEL_PACK_BUFFER_BINDING, &pack_buffer);
    for (size_t i = first; i < npack; i++) {
        gl.get_integerv(pack[i], &saved[i]);
        gl.pixel_storei(pack[i], pack[i] == GL_PACK_ALIGNMENT ? 1 : 0);
    }
    if (pack_buffer)
        gl.bind_buffer(GL_PIXEL_PACK_BUFFER, 0);

    /* Every texture described, sized and read before the reply starts: a
     * reply is whole or not sent. */
    static struct Texture textures[MAX_UNITS];
    static void *pixels[MAX_UNITS][MAX_LEVELS];
    static GLfloat values[MAX_UNITS][NPARAMETERS][4];
    static int has[MAX_UNITS][NPARAMETERS];
    const char *why = NULL;
    uint64_t total = 0;
    for (int k = 0; k < want_count && !why; k++) {
        if (!known_target(want_targets[k])) {
            why = "a texture target the readback does not take";
            break;
        }
        GLint saved = 0;
        if (!select_unit(k, &saved))
            why = "the texture an image unit holds is not of the target the converter asked for";
        describe(&textures[k], want_targets[k]);
        unselect_unit(k, saved);
        for (int i = 0; i < MAX_LEVELS; i++)
            total += level_bytes(&textures[k], i);
        if (multisample(want_targets[k]) &&
            (!gl.get_integer64i_v || !gl.create_shader || !gl.shader_source || !gl.compile_shader ||
             !gl.create_program || !gl.attach_shader || !gl.link_program || !gl.get_programiv || !gl.use_program ||
             !gl.get_uniform_location || !gl.uniform1i || !gl.gen_buffers || !gl.buffer_data ||
             !gl.bind_buffer_base || !gl.bind_buffer_range || !gl.dispatch_compute || !gl.memory_barrier ||
             !gl.map_buffer_range || !gl.unmap_buffer || !gl.delete_buffers || !gl.delete_program ||
             !gl.delete_shader))
            why = "a multisample texture is read by a compute shader, which the replay's GL lacks";
    }
    if (!why && total > MAX_REPLY_BYTES)
        why = "the textures would take more than 1 GiB to read back";
    for (int k = 0; k < want_count && !why; k++) {
        GLint saved = 0;
        select_unit(k, &saved);   /* (its target checked above) */
        for (int i = 0; i < MAX_LEVELS && !why; i++) {
            pixels[k][i] = NULL;
            if (!textures[k].size[i][0])
                continue;
            uint64_t n = level_bytes(&textures[k], i);
            pixels[k][i] = calloc(n ? n : 1, 1);
            if (!pixels[k][i])
                die();
            if (multisample(textures[k].target)) {
                int read = read_multisample(&textures[k], unit_of(k), pixels[k][i]);
                if (read < 0)
                    why = "a multisample texture read while the replay's program in use is deleted (its own "
                          "compute shader would free that program)";
                else if (!read)
                    why = "a multisample texture the replay's compute shader could not read";
            } else if (!read_level(&textures[k], i, pixels[k][i])) {
                why = es ? "an OpenGL ES texture whose images glReadPixels cannot read in a format that gives "
                           "their values back (a normalized one of channels wider than 8 bits but RGB10_A2, one a "
                           "framebuffer cannot hold) is not read back"
                         : "a texture whose image glGetTexImage does not read (a stencil-only format) is not read "
                           "back";
            }
        }
        for (size_t j = 0; j < NPARAMETERS; j++) {
            while (gl.get_error() != GL_NO_ERROR)
                ;
            gl.get_tex_parameterfv(textures[k].target, parameters[j], values[k][j]);
            has[k][j] = gl.get_error() == GL_NO_ERROR;   /* one the context has not (OpenGL ES's LOD bias) */
        }
        unselect_unit(k, saved);
    }
    if (why) {
        refuse(why);
    } else {
        put("RBTX", 4);
        put_u32((uint32_t)want_count);
        for (int k = 0; k < want_count; k++) {
            const struct Texture *t = &textures[k];
            uint32_t nparams = multisample(t->target) ? 1 : 0;   /* its samples: GL_TEXTURE_SAMPLES */
            for (size_t j = 0; j < NPARAMETERS; j++)
                nparams += (uint32_t)has[k][j];
            put_u32((uint32_t)want_units[k]);
            put_u32(t->target);
            put_u32((uint32_t)t->internal);
            put_u32(nparams);
            if (multisample(t->target)) {
                const GLfloat samples[4] = {(GLfloat)t->samples, (GLfloat)t->fixed, (GLfloat)t->layers, 0};
                put_u32(GL_TEXTURE_SAMPLES);
                put(samples, 16);
            }
            for (size_t j = 0; j < NPARAMETERS; j++) {
                if (!has[k][j])
                    continue;
                put_u32(parameters[j]);
                put(values[k][j], 16);
            }
            put_u32((uint32_t)t->levels);
            for (GLint i = 0; i < MAX_LEVELS; i++) {
                if (!t->size[i][0])
                    continue;
                uint64_t n = level_bytes(t, i);
                put_u32((uint32_t)i);
                put_u32((uint32_t)t->size[i][0]);
                put_u32((uint32_t)t->size[i][1]);
                put_u32((uint32_t)t->size[i][2]);
                put_u32(t->format);
                put_u32(t->type);
                put(&n, 8);
                put(pixels[k][i], n);
            }
        }
    }
    for (int k = 0; k < want_count; k++)
        for (int i = 0; i < MAX_LEVELS; i++) {
            free(pixels[k][i]);
            pixels[k][i] = NULL;
        }
    while (gl.get_error() != GL_NO_ERROR)
        ;   /* the reads' own errors are not the capture's */
    for (size_t i = first; i < npack; i++)
        gl.pixel_storei(pack[i], saved[i]);
    if (pack_buffer)
        gl.bind_buffer(GL_PIXEL_PACK_BUFFER, (GLuint)pack_buffer);
    gl.active_texture((GLenum)active);
}

static int open_fifos(void)
{
    if (requests >= 0)
        return 1;
    const char *dir = getenv("RBCD_TEXTURE_FIFOS");
    if (!dir || !real_get_proc)
        return 0;
    char path[4096];
    snprintf(path, sizeof path, "%s/requests", dir);
    requests = open(path, O_RDONLY | O_CLOEXEC);
    snprintf(path, sizeof path, "%s/replies", dir);
    replies = open(path, O_WRONLY | O_CLOEXEC);
    if (requests < 0 || replies < 0)
        die();
    gl.get_integerv = (void (*)(GLenum, GLint *))real_get_proc("glGetIntegerv");
    gl.active_texture = (void (*)(GLenum))real_get_proc("glActiveTexture");
    gl.pixel_storei = (void (*)(GLenum, GLint))real_get_proc("glPixelStorei");
    gl.bind_buffer = (void (*)(GLenum, GLuint))real_get_proc("glBindBuffer");
    gl.get_tex_level_parameteriv =
        (void (*)(GLenum, GLint, GLenum, GLint *))real_get_proc("glGetTexLevelParameteriv");
    gl.get_tex_image = (void (*)(GLenum, GLint, GLenum, GLenum, void *))real_get_proc("glGetTexImage");
    gl.get_error = (GLenum(*)(void))real_get_proc("glGetError");
    gl.get_tex_parameterfv = (void (*)(GLenum, GLenum, GLfloat *))real_get_proc("glGetTexParameterfv");
    gl.tex_parameteri = (void (*)(GLenum, GLenum, GLint))real_get_proc("glTexParameteri");
    gl.get_string = (const GLubyte *(*)(GLenum))real_get_proc("glGetString");
    gl.gen_framebuffers = (void (*)(GLsizei, GLuint *))real_get_proc("glGenFramebuffers");
    gl.delete_framebuffers = (void (*)(GLsizei, const GLuint *))real_get_proc("glDeleteFramebuffers");
    gl.bind_framebuffer = (void (*)(GLenum, GLuint))real_get_proc("glBindFramebuffer");
    gl.framebuffer_texture_2d = (void (*)(GLenum, GLenum, GLenum, GLuint, GLint))real_get_proc("glFramebufferTexture2D");
    gl.framebuffer_texture_layer =
        (void (*)(GLenum, GLenum, GLuint, GLint, GLint))real_get_proc("glFramebufferTextureLayer");
    gl.check_framebuffer_status = (GLenum(*)(GLenum))real_get_proc("glCheckFramebufferStatus");
    gl.read_pixels = (void (*)(GLint, GLint, GLsizei, GLsizei, GLenum, GLenum, void *))real_get_proc("glReadPixels");
    gl.bind_texture = (void (*)(GLenum, GLuint))real_get_proc("glBindTexture");
    gl.get_integeri_v = (void (*)(GLenum, GLuint, GLint *))real_get_proc("glGetIntegeri_v");
    /* Those of a multisample texture's read: checked when one is read. */
    gl.get_integer64i_v = (void (*)(GLenum, GLuint, GLint64 *))real_get_proc("glGetInteger64i_v");
    gl.create_shader = (GLuint(*)(GLenum))real_get_proc("glCreateShader");
    gl.shader_source = (void (*)(GLuint, GLsizei, const GLchar *const *, const GLint *))real_get_proc("glShaderSource");
    gl.compile_shader = (void (*)(GLuint))real_get_proc("glCompileShader");
    gl.create_program = (GLuint(*)(void))real_get_proc("glCreateProgram");
    gl.attach_shader = (void (*)(GLuint, GLuint))real_get_proc("glAttachShader");
    gl.link_program = (void (*)(GLuint))real_get_proc("glLinkProgram");
    gl.get_programiv = (void (*)(GLuint, GLenum, GLint *))real_get_proc("glGetProgramiv");
    gl.use_program = (void (*)(GLuint))real_get_proc("glUseProgram");
    gl.get_uniform_location = (GLint(*)(GLuint, const GLchar *))real_get_proc("glGetUniformLocation");
    gl.uniform1i = (void (*)(GLint, GLint))real_get_proc("glUniform1i");
    gl.gen_buffers = (void (*)(GLsizei, GLuint *))real_get_proc("glGenBuffers");
    gl.buffer_data = (void (*)(GLenum, GLsizeiptr, const void *, GLenum))real_get_proc("glBufferData");
    gl.bind_buffer_base = (void (*)(GLenum, GLuint, GLuint))real_get_proc("glBindBufferBase");
    gl.bind_buffer_range = (void (*)(GLenum, GLuint, GLuint, GLintptr, GLsizeiptr))real_get_proc("glBindBufferRange");
    gl.dispatch_compute = (void (*)(GLuint, GLuint, GLuint))real_get_proc("glDispatchCompute");
    gl.memory_barrier = (void (*)(GLbitfield))real_get_proc("glMemoryBarrier");
    gl.map_buffer_range = (void *(*)(GLenum, GLintptr, GLsizeiptr, GLbitfield))real_get_proc("glMapBufferRange");
    gl.unmap_buffer = (GLboolean(*)(GLenum))real_get_proc("glUnmapBuffer");
    gl.delete_buffers = (void (*)(GLsizei, const GLuint *))real_get_proc("glDeleteBuffers");
    gl.delete_program = (void (*)(GLuint))real_get_proc("glDeleteProgram");
    gl.delete_shader = (void (*)(GLuint))real_get_proc("glDeleteShader");
    if (!gl.get_integerv || !gl.active_texture || !gl.pixel_storei || !gl.bind_buffer ||
        !gl.get_tex_level_parameteriv || !gl.get_tex_image || !gl.get_tex_parameterfv || !gl.tex_parameteri ||
        !gl.get_error ||
        !gl.get_string ||
        !gl.gen_framebuffers || !gl.delete_framebuffers || !gl.bind_framebuffer || !gl.framebuffer_texture_2d ||
        !gl.check_framebuffer_status || !gl.read_pixels || !gl.bind_texture || !gl.get_integeri_v)
        die();
    return 1;
}

static void marker(const GLchar *message)
{
    if (!message || !open_fifos())
        return;
    char *end;
    long long call = strtoll(message, &end, 10);
    if (end == message)
        return;
    if (want < 0)
        next_request();
    while (want >= 0 && call > want) {   /* the call asked for was not replayed (no context current) */
        char text[160];
        snprintf(text, sizeof text, "Mesa's replay did not make call %lld (no GL context current there)", want);
        refuse(text);
        next_request();
    }
    if (call == want) {
        const char *version = (const char *)gl.get_string(GL_VERSION);
        es = version && strncmp(version, "OpenGL ES", 9) == 0;
        answer();
        want = -1;
    }
}

static void insert(GLenum source, GLenum type, GLuint id, GLenum severity, GLsizei length, const GLchar *buf)
{
    marker(buf);
    if (real_insert)
        real_insert(source, type, id, severity, length, buf);
}

static void insert_khr(GLenum source, GLenum type, GLuint id, GLenum severity, GLsizei length, const GLchar *buf)
{
    marker(buf);
    if (real_insert_khr)
        real_insert_khr(source, type, id, severity, length, buf);
}

static void *get_proc(const char *name)
{
    void *p = real_get_proc(name);
    if (p && strcmp(name, "glDebugMessageInsert") == 0) {
        real_insert = (DebugMessageInsert)p;
        return (void *)insert;
    }
    if (p && strcmp(name, "glDebugMessageInsertKHR") == 0) {
        real_insert_khr = (DebugMessageInsert)p;
        return (void *)insert_khr;
    }
    return p;
}

void *dlsym(void *handle, const char *name)
{
    void *p = next_lookup(handle, name);
    if (p && (strcmp(name, "glXGetProcAddressARB") == 0 || strcmp(name, "glXGetProcAddress") == 0 ||
              strcmp(name, "eglGetProcAddress") == 0)) {
        real_get_proc = (GetProc)p;
        return (void *)get_proc;
    }
    return p;
}

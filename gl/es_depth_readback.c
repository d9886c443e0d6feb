/* Preloaded into glretrace by `rbcd-gl2rbt --check-depth` on OpenGL ES
 * captures (docs/gl-capture.md, "The Mesa depth check").
 *
 * glretrace -D dumps a depth buffer with glReadPixels(GL_DEPTH_COMPONENT,
 * GL_FLOAT). OpenGL ES (with NV_read_depth, which Mesa exposes) accepts
 * only the type that matches the buffer, GL_UNSIGNED_INT for a fixed-point
 * one, so Mesa answers GL_INVALID_OPERATION and glretrace dumps no depth.
 * This library wraps glReadPixels where glretrace looks it up (dlsym on the
 * GL library's handle): a float depth read that fails with
 * GL_INVALID_OPERATION is made again as GL_UNSIGNED_INT and each value is
 * converted as Mesa converts a d-bit fixed-point depth to float on desktop
 * GL, (value >> (32 - d)) / (2^d - 1), so the check reads an ES capture's
 * depth as it reads a desktop one's.
 *
 * The state dump also describes every texture bound at every unit, which
 * glretrace does on OpenGL ES by probing with glTexSubImage and asserts on
 * the targets it has no probe for (2D arrays, cube map arrays,
 * multisample and buffer textures): a capture that leaves one bound at
 * the dumped call would abort the dump. The check needs no texture, so
 * glGetIntegerv answers 0 for each texture binding (glretrace asks for
 * them only to dump state). Every other call passes through unchanged. */
#define _GNU_SOURCE
#include <dlfcn.h>
#include <stdint.h>
#include <string.h>

#include <GLES2/gl2.h>

#include "next_dlsym.h"

typedef void (*ReadPixels)(GLint, GLint, GLsizei, GLsizei, GLenum, GLenum, void *);
typedef GLenum (*GetError)(void);
typedef void (*GetIntegerv)(GLenum, GLint *);

static ReadPixels real_read_pixels;
static GetError real_get_error;
static GetIntegerv real_get_integerv;

/* GL_TEXTURE_BINDING_2D, _3D, _CUBE_MAP, _2D_ARRAY, _CUBE_MAP_ARRAY,
 * _2D_MULTISAMPLE, _2D_MULTISAMPLE_ARRAY and _BUFFER. */
static const GLenum texture_bindings[] = {0x8069, 0x806A, 0x8514, 0x8C1D, 0x900A, 0x9104, 0x9105, 0x8C2C};

static void get_integerv(GLenum pname, GLint *params)
{
    real_get_integerv(pname, params);
    for (size_t i = 0; i < sizeof texture_bindings / sizeof texture_bindings[0]; i++)
        if (pname == texture_bindings[i] && params)
            *params = 0;
}

static void read_pixels(GLint x, GLint y, GLsizei w, GLsizei h, GLenum format, GLenum type, void *pixels)
{
    real_read_pixels(x, y, w, h, format, type, pixels);
    if (format != GL_DEPTH_COMPONENT || type != GL_FLOAT || !real_get_error || !real_get_integerv || w <= 0 ||
        h <= 0 || !pixels)
        return;
    GLenum err = real_get_error();
    if (err != GL_INVALID_OPERATION)
        return;   /* read as asked, or failed for a reason a retry would not mend */
    /* glretrace resets the pack state (alignment 4, no row length or skip):
     * 4-byte values fill the rows as the floats would. */
    real_read_pixels(x, y, w, h, GL_DEPTH_COMPONENT, GL_UNSIGNED_INT, pixels);
    if (real_get_error() != GL_NO_ERROR)
        return;
    GLint bits = 0;
    real_get_integerv(GL_DEPTH_BITS, &bits);
    real_get_error();
    if (bits <= 0 || bits > 32)
        bits = 32;
    const double max = (double)((bits == 32) ? UINT32_MAX : ((UINT32_C(1) << bits) - 1));
    uint32_t *u = pixels;
    float *f = pixels;
    for (size_t i = 0, n = (size_t)w * (size_t)h; i < n; i++)
        f[i] = (float)((double)(u[i] >> (32 - bits)) / max);
}

void *dlsym(void *handle, const char *name)
{
    void *p = next_lookup(handle, name);
    if (p && strcmp(name, "glReadPixels") == 0) {
        real_read_pixels = (ReadPixels)p;
        real_get_error = (GetError)next_lookup(handle, "glGetError");
        real_get_integerv = (GetIntegerv)next_lookup(handle, "glGetIntegerv");
        return (void *)read_pixels;
    }
    if (p && strcmp(name, "glGetIntegerv") == 0) {
        real_get_integerv = (GetIntegerv)p;
        return (void *)get_integerv;
    }
    return p;
}

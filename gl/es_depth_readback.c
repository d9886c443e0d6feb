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
 * depth as it reads a desktop one's. Every other call passes through
 * unchanged. */
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
    return p;
}

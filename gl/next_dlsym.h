/* The dlsym a preloaded library wrapping dlsym passes lookups on to (the
 * libraries glretrace is run with: es_depth_readback.c, texture_readback.c).
 * glibc 2.34 moved dlsym into libc under a new version; older ones have the
 * x86-64 base version. */
#ifndef RBCD_GL_NEXT_DLSYM_H
#define RBCD_GL_NEXT_DLSYM_H

#include <dlfcn.h>

typedef void *(*Dlsym)(void *, const char *);

/* `name` looked up in `handle` by the dlsym the library's own wraps. */
static void *next_lookup(void *handle, const char *name)
{
    static Dlsym next;
    if (!next)
        next = (Dlsym)dlvsym(RTLD_NEXT, "dlsym", "GLIBC_2.34");
    if (!next)
        next = (Dlsym)dlvsym(RTLD_NEXT, "dlsym", "GLIBC_2.2.5");
    return next ? next(handle, name) : NULL;
}

#endif

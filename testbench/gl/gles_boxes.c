/* A small OpenGL ES 2.0 program of the project's own, through EGL on X11:
 * captured under Xvfb with `apitrace trace --api egl` and converted by
 * rbcd-gl2rbt in the tests (testbench/gl/test_gl2rbt_shaders.py, whose
 * docstring gives what each frame must become).
 *
 *   gles_boxes [WIDTH HEIGHT [layers]]   (default 128 96; the window is the screen)
 *
 * ES 2.0 as phones ran it: a "#version 100" vertex shader with one uniform
 * mat4, attributes from client memory (glVertexAttribPointer with a
 * pointer, no buffer bound) and indices from client memory, a box from a
 * buffer object, attribute locations chosen by glBindAttribLocation.
 * Collisionable objects are tagged with KHR_debug groups "rbcd-object"
 * (glPushDebugGroupKHR, as ES names it).
 *
 * With "layers" (an OpenGL ES 3.2 context), frame 1 ends with one more draw,
 * object 9: the unit cube's first triangle (z = 1) moved by what a "#version 320
 * es" vertex shader reads from three textures framebuffer objects cleared
 * (so the converter must read them back from Mesa's replay): face +X of an
 * RGBA32F cube map, slice 1 of an RGBA32F 3D texture, layer 1 of a
 * DEPTH_COMPONENT24 2D array (each other face, slice and layer another
 * value); together they move the triangle by (-0.75, -0.5, -1.5), as
 * gl_shaders' faults do. */
#include <EGL/egl.h>
#include <GLES3/gl32.h>
#include <GLES2/gl2ext.h>
#include <X11/Xlib.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "unit_cube.h"

static const char* vertex_source =
    "#version 100\n"
    "uniform mat4 mvp;\n"
    "attribute vec3 position;\n"
    "void main() { gl_Position = mvp * vec4(position, 1.0); }\n";
static const char* fragment_source =
    "#version 100\n"
    "precision mediump float;\n"
    "void main() { gl_FragColor = vec4(1.0); }\n";

/* The "layers" draw's shaders. */
static const char* layers_vertex_source =
    "#version 320 es\n"
    "uniform highp samplerCube cube;\n"
    "uniform highp sampler3D volume;\n"
    "uniform highp sampler2DArray depths;\n"
    "in vec3 position;\n"
    "void main() {\n"
    "    float d = texelFetch(depths, ivec3(0, 0, 1), 0).r;\n"
    "    gl_Position = vec4(position, 1.0) + textureLod(cube, vec3(1.0, 0.2, -0.3), 0.0) +\n"
    "                  texelFetch(volume, ivec3(1, 0, 1), 0) + vec4(-2.0, -1.0, -2.0, 0.0) * d;\n"
    "}\n";
static const char* layers_fragment_source =
    "#version 320 es\n"
    "precision mediump float;\n"
    "out vec4 colour;\n"
    "void main() { colour = vec4(1.0); }\n";

static GLushort triangles[36];
static GLint mvp_at;
static int width, height;
static PFNGLPUSHDEBUGGROUPKHRPROC push_group;
static PFNGLPOPDEBUGGROUPKHRPROC pop_group;

/* mvp = ortho(0, w, 0, h, -100, 100) * box: window depth 0.5 - z / 200. */
static void box_matrix(float x0, float y0, float z0, float x1, float y1, float z1) {
    float m[16] = {0};
    m[0] = 2.0f / width * (x1 - x0), m[5] = 2.0f / height * (y1 - y0), m[10] = -0.01f * (z1 - z0), m[15] = 1;
    m[12] = 2.0f / width * x0 - 1, m[13] = 2.0f / height * y0 - 1, m[14] = -0.01f * z0;
    glUniformMatrix4fv(mvp_at, 1, GL_FALSE, m);
}

static GLuint compile(GLenum kind, const char* text) {
    GLuint s = glCreateShader(kind);
    glShaderSource(s, 1, &text, NULL);
    glCompileShader(s);
    GLint ok = 0;
    glGetShaderiv(s, GL_COMPILE_STATUS, &ok);
    if (!ok) {
        fprintf(stderr, "gles_boxes: a shader does not compile\n");
        exit(1);
    }
    return s;
}

/* A program of the two stages, "position" at attribute 1, in use. */
static GLuint use_program(const char* vertex, const char* fragment) {
    GLuint p = glCreateProgram();
    glAttachShader(p, compile(GL_VERTEX_SHADER, vertex));
    glAttachShader(p, compile(GL_FRAGMENT_SHADER, fragment));
    glBindAttribLocation(p, 1, "position");
    glLinkProgram(p);
    glUseProgram(p);
    return p;
}

/* A texture of `target` on texture unit `unit`, immutable storage of one
 * level, nearest filtering. */
static GLuint layered_texture(GLenum unit, GLenum target, GLenum format, GLsizei w, GLsizei h, GLsizei d) {
    GLuint tex;
    glActiveTexture(unit);
    glGenTextures(1, &tex);
    glBindTexture(target, tex);
    if (target == GL_TEXTURE_CUBE_MAP)
        glTexStorage2D(target, 1, format, w, h);
    else
        glTexStorage3D(target, 1, format, w, h, d);
    glTexParameteri(target, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    glTexParameteri(target, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    glActiveTexture(GL_TEXTURE0);
    return tex;
}

/* The "layers" draw (see the header comment): the textures cleared through
 * a framebuffer object, image by image, then the triangle. */
static void layers_draw(void) {
    static const GLfloat other[4] = {9, 9, 9, 0}, face[4] = {-0.25f, 0, -0.5f, 0}, slice[4] = {0, -0.25f, -0.5f, 0};
    static const GLfloat far_depth = 1.0f, depth = 0.25f;
    GLuint cube_map = layered_texture(GL_TEXTURE2, GL_TEXTURE_CUBE_MAP, GL_RGBA32F, 1, 1, 1);
    GLuint volume = layered_texture(GL_TEXTURE3, GL_TEXTURE_3D, GL_RGBA32F, 2, 2, 2);
    GLuint depths = layered_texture(GL_TEXTURE4, GL_TEXTURE_2D_ARRAY, GL_DEPTH_COMPONENT24, 2, 2, 2);
    GLuint fb;
    glGenFramebuffers(1, &fb);
    glBindFramebuffer(GL_FRAMEBUFFER, fb);
    for (GLenum f = 0; f < 6; ++f) {
        glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_CUBE_MAP_POSITIVE_X + f, cube_map, 0);
        glClearBufferfv(GL_COLOR, 0, f == 0 ? face : other);
    }
    for (GLint layer = 0; layer < 2; ++layer) {
        glFramebufferTextureLayer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, volume, 0, layer);
        glClearBufferfv(GL_COLOR, 0, layer == 1 ? slice : other);
    }
    glFramebufferTextureLayer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, 0, 0, 0);
    for (GLint layer = 0; layer < 2; ++layer) {
        glFramebufferTextureLayer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, depths, 0, layer);
        glClearBufferfv(GL_DEPTH, 0, layer == 1 ? &depth : &far_depth);
    }
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    GLuint p = use_program(layers_vertex_source, layers_fragment_source);
    glUniform1i(glGetUniformLocation(p, "cube"), 2);
    glUniform1i(glGetUniformLocation(p, "volume"), 3);
    glUniform1i(glGetUniformLocation(p, "depths"), 4);
    glVertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, 0, cube);
    push_group(GL_DEBUG_SOURCE_APPLICATION_KHR, 9, -1, "rbcd-object");
    glDrawArrays(GL_TRIANGLES, 0, 3);
    pop_group();
}

int main(int argc, char** argv) {
    width = argc > 2 ? atoi(argv[1]) : 128, height = argc > 2 ? atoi(argv[2]) : 96;
    const int layers = argc > 3 && !strcmp(argv[3], "layers");
    if (argc > 3 && !layers) {
        fprintf(stderr, "gles_boxes: no fault %s (layers is the one)\n", argv[3]);
        return 1;
    }
    Display* x = XOpenDisplay(NULL);
    if (!x) {
        fprintf(stderr, "gles_boxes: cannot open display (run under Xvfb)\n");
        return 1;
    }
    Window win = XCreateSimpleWindow(x, RootWindow(x, DefaultScreen(x)), 0, 0, width, height, 0, 0, 0);
    XSelectInput(x, win, StructureNotifyMask);
    XMapWindow(x, win);
    for (XEvent ev;;) {
        XNextEvent(x, &ev);
        if (ev.type == MapNotify) break;
    }
    EGLDisplay dpy = eglGetDisplay((EGLNativeDisplayType)x);
    EGLint major, minor, n = 0;
    const EGLint config_attrs[] = {EGL_RENDERABLE_TYPE, EGL_OPENGL_ES2_BIT, EGL_SURFACE_TYPE, EGL_WINDOW_BIT,
                                   EGL_DEPTH_SIZE, 24, EGL_NONE};
    EGLConfig config;
    if (!eglInitialize(dpy, &major, &minor) || !eglChooseConfig(dpy, config_attrs, &config, 1, &n) || n < 1) {
        fprintf(stderr, "gles_boxes: no EGL configuration for OpenGL ES 2 with a 24-bit depth buffer\n");
        return 1;
    }
    EGLSurface surface = eglCreateWindowSurface(dpy, config, (EGLNativeWindowType)win, NULL);
    const EGLint ctx_attrs[] = {EGL_CONTEXT_CLIENT_VERSION, layers ? 3 : 2, EGL_NONE};
    EGLContext ctx = eglCreateContext(dpy, config, EGL_NO_CONTEXT, ctx_attrs);
    if (surface == EGL_NO_SURFACE || ctx == EGL_NO_CONTEXT || !eglMakeCurrent(dpy, surface, surface, ctx)) {
        fprintf(stderr, "gles_boxes: no OpenGL ES 2 context\n");
        return 1;
    }
    push_group = (PFNGLPUSHDEBUGGROUPKHRPROC)eglGetProcAddress("glPushDebugGroupKHR");
    pop_group = (PFNGLPOPDEBUGGROUPKHRPROC)eglGetProcAddress("glPopDebugGroupKHR");
    if (!push_group || !pop_group) {
        fprintf(stderr, "gles_boxes: the GL lacks KHR_debug\n");
        return 1;
    }

    GLuint prog = use_program(vertex_source, fragment_source);
    mvp_at = glGetUniformLocation(prog, "mvp");
    for (int f = 0; f < 6; ++f) {
        const GLushort b = (GLushort)(4 * f);
        const GLushort t[6] = {b, (GLushort)(b + 1), (GLushort)(b + 2), b, (GLushort)(b + 2), (GLushort)(b + 3)};
        memcpy(triangles + 6 * f, t, sizeof t);
    }
    GLuint vbo;
    glGenBuffers(1, &vbo);
    glBindBuffer(GL_ARRAY_BUFFER, vbo);
    glBufferData(GL_ARRAY_BUFFER, sizeof cube, cube, GL_STATIC_DRAW);
    glBindBuffer(GL_ARRAY_BUFFER, 0);
    static const GLfloat floor_quad[4][3] = {{0, 40, -50}, {40, 40, -50}, {40, 80, -50}, {0, 80, -50}};

    glEnable(GL_DEPTH_TEST);
    glEnable(GL_CULL_FACE);
    glEnableVertexAttribArray(1);
    for (int frame = 0; frame < 2; ++frame) {
        glViewport(0, 0, width, height);
        glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
        /* Boxes 1 and 2 from client memory, indexed from client memory. */
        glVertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, 0, cube);
        push_group(GL_DEBUG_SOURCE_APPLICATION_KHR, 1, -1, "rbcd-object");
        box_matrix(8, 8, -20, 28, 28, -10);
        glDrawElements(GL_TRIANGLES, 36, GL_UNSIGNED_SHORT, triangles);
        pop_group();
        push_group(GL_DEBUG_SOURCE_APPLICATION_KHR, 2, -1, "rbcd-object");
        box_matrix(20, 16, -15, 40, 36, -5);
        glDrawElements(GL_TRIANGLES, 36, GL_UNSIGNED_SHORT, triangles);
        pop_group();
        /* Box 3 from the buffer object; frame 1 moves it 30 right. */
        glBindBuffer(GL_ARRAY_BUFFER, vbo);
        glVertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, 0, 0);
        glBindBuffer(GL_ARRAY_BUFFER, 0);
        push_group(GL_DEBUG_SOURCE_APPLICATION_KHR, 3, -1, "rbcd-object");
        box_matrix(60.0f + 30 * frame, 8, -10, 70.0f + 30 * frame, 18, -5);
        glDrawElements(GL_TRIANGLES, 36, GL_UNSIGNED_SHORT, triangles);
        pop_group();
        /* The floor, untagged, as a fan from client memory. */
        glVertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, 0, floor_quad);
        box_matrix(0, 0, 0, 1, 1, 1);
        glDrawArrays(GL_TRIANGLE_FAN, 0, 4);
        if (layers && frame == 1)
            layers_draw();
        eglSwapBuffers(dpy, surface);
    }
    eglMakeCurrent(dpy, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
    eglTerminate(dpy);
    XCloseDisplay(x);
    return 0;
}

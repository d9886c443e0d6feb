/* A small GL 1.x program of the project's own, captured under Xvfb with
 * `apitrace trace` and converted by rbcd-gl2rbt in the tests
 * (testbench/gl/CMakeLists.txt). Every frame is built so that what the
 * converter must produce can be worked out by hand: docs/gl-capture.md gives
 * the expected fragments, `c` tags and pairs of each frame.
 *
 *   gl_boxes [WIDTH HEIGHT [FAULT]]   (default 128 96; the window is the screen)
 *
 * FAULT adds one call in frame 1 that the converter must refuse, naming it:
 * nan (a NaN matrix), index (an index past a buffer's vertices), ortho (an
 * empty glOrtho volume), list (a display list), shader (a draw under a
 * program), line (glPolygonMode GL_LINE), underflow (glPopMatrix on an
 * empty stack). FAULT point is no fault: an object scaled to a point.
 * FAULT readother is no fault either: frames 0 and 1 drawn with a second,
 * 16 x 16 window as the context's read drawable (glXMakeContextCurrent),
 * frame 2 reading the window it draws into.
 * FAULT glsl is no fault: the array draws under GLSL 1.20 programs that read
 * the compatibility profile's state (a converter without it refuses them):
 * box 1 and the floor by gl_ModelViewProjectionMatrix * gl_Vertex, box 2 by
 * ftransform(); in frame 2 box 1's vertices come through generic attribute
 * 0 (glVertexAttribPointer), which gl_Vertex reads. Immediate-mode draws stay
 * fixed-function. The same fragments as without a program.
 *
 * Collisionable objects are tagged as rbcd-gl2rbt reads them: a KHR_debug
 * group "rbcd-object" whose id is the object id, or an EXT_debug_marker group
 * "rbcd-object N". Geometry comes through every path the converter emulates:
 * client arrays (glDrawArrays, glDrawElements), a buffer object
 * (glDrawRangeElements), immediate mode, display-independent matrix calls. */
#define GL_GLEXT_PROTOTYPES 1
#include <GL/gl.h>
#include <GL/glext.h>
#include <GL/glx.h>
#include <X11/Xlib.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static PFNGLPUSHDEBUGGROUPPROC push_group;
static PFNGLPOPDEBUGGROUPPROC pop_group;
static PFNGLPUSHGROUPMARKEREXTPROC push_marker;
static PFNGLPOPGROUPMARKEREXTPROC pop_marker;
static PFNGLGENBUFFERSPROC gen_buffers;
static PFNGLBINDBUFFERPROC bind_buffer;
static PFNGLBUFFERDATAPROC buffer_data;
static PFNGLBUFFERSUBDATAPROC buffer_sub_data;

static const char* fault = "";
static PFNGLCREATESHADERPROC create_shader;
static PFNGLSHADERSOURCEPROC shader_source;
static PFNGLCOMPILESHADERPROC compile_shader;
static PFNGLCREATEPROGRAMPROC create_program;
static PFNGLATTACHSHADERPROC attach_shader;
static PFNGLLINKPROGRAMPROC link_program;
static PFNGLUSEPROGRAMPROC use_program;
static PFNGLVERTEXATTRIBPOINTERPROC attrib_pointer;
static PFNGLENABLEVERTEXATTRIBARRAYPROC enable_attrib;
static PFNGLDISABLEVERTEXATTRIBARRAYPROC disable_attrib;
/* The glsl mode's programs (0 otherwise) and whether box_client gives its
 * vertices through generic attribute 0. */
static GLuint glsl_mvp, glsl_ftransform;
static int generic_vertex;

static void begin_object(unsigned id);
static void end_object(void);
static void box_client(float x0, float y0, float z0, float x1, float y1, float z1);

/* The one refusable call of frame 1 (see the header comment). */
static void inject_fault(void) {
    static const GLushort past[3] = {0, 1, 20};
    if (!strcmp(fault, "nan")) {
        const GLfloat m[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, NAN, 0, 0, 0, 0, 1};
        glLoadMatrixf(m);
    } else if (!strcmp(fault, "index")) {
        GLuint b[2];
        const float v[8][3] = {{0}};
        gen_buffers(2, b);
        bind_buffer(GL_ARRAY_BUFFER, b[0]);
        buffer_data(GL_ARRAY_BUFFER, sizeof v, v, GL_STATIC_DRAW);
        bind_buffer(GL_ELEMENT_ARRAY_BUFFER, b[1]);
        buffer_data(GL_ELEMENT_ARRAY_BUFFER, sizeof past, past, GL_STATIC_DRAW);
        glEnableClientState(GL_VERTEX_ARRAY);
        glVertexPointer(3, GL_FLOAT, 0, (const void*)0);
        glDrawElements(GL_TRIANGLES, 3, GL_UNSIGNED_SHORT, (const void*)0);
        glDisableClientState(GL_VERTEX_ARRAY);
        bind_buffer(GL_ARRAY_BUFFER, 0);
        bind_buffer(GL_ELEMENT_ARRAY_BUFFER, 0);
    } else if (!strcmp(fault, "ortho")) {
        glOrtho(0, 0, 0, 1, -1, 1);
    } else if (!strcmp(fault, "list")) {
        const GLuint l = glGenLists(1);
        glNewList(l, GL_COMPILE);
        glRectf(0, 0, 4, 4);
        glEndList();
        glCallList(l);
    } else if (!strcmp(fault, "shader")) {
        const char* src = "void main() { gl_Position = ftransform(); }";
        const GLuint sh = create_shader(GL_VERTEX_SHADER), prog = create_program();
        shader_source(sh, 1, &src, NULL);
        compile_shader(sh);
        attach_shader(prog, sh);
        link_program(prog);
        use_program(prog);
        glRectf(0, 0, 4, 4);
        use_program(0);
    } else if (!strcmp(fault, "line")) {
        glPolygonMode(GL_FRONT_AND_BACK, GL_LINE);
    } else if (!strcmp(fault, "underflow")) {
        glMatrixMode(GL_PROJECTION);
        glPopMatrix();
        glMatrixMode(GL_MODELVIEW);
    } else if (!strcmp(fault, "point")) {
        /* Not a fault: object 9 scaled to a point, as OpenArena shrinks some
         * effects. It covers no pixel and has no surface, so it must not
         * reach the geometry either (every triangle welds into one vertex). */
        glPushMatrix();
        glTranslatef(90, 20, -10);
        glScalef(0, 0, 0);
        begin_object(9); box_client(0, 0, 0, 10, 10, 10); end_object();
        glPopMatrix();
    }
}

static void begin_object(unsigned id) { push_group(GL_DEBUG_SOURCE_APPLICATION, id, -1, "rbcd-object"); }
static void end_object(void) { pop_group(); }

/* An axis-aligned box [x0,x1] x [y0,y1] x [z0,z1] as 12 triangles, counter-
 * clockwise seen from outside. */
static void box_arrays(float x0, float y0, float z0, float x1, float y1, float z1, float v[8][3], GLushort idx[36]) {
    for (int i = 0; i < 8; ++i) {
        v[i][0] = (i & 1) ? x1 : x0;
        v[i][1] = (i & 2) ? y1 : y0;
        v[i][2] = (i & 4) ? z1 : z0;
    }
    static const GLushort faces[6][4] = {
        {0, 2, 3, 1}, /* z0, normal -z */
        {4, 5, 7, 6}, /* z1, normal +z */
        {0, 1, 5, 4}, /* y0 */
        {2, 6, 7, 3}, /* y1 */
        {0, 4, 6, 2}, /* x0 */
        {1, 3, 7, 5}, /* x1 */
    };
    for (int f = 0; f < 6; ++f) {
        const GLushort* q = faces[f];
        GLushort* o = idx + 6 * f;
        o[0] = q[0]; o[1] = q[1]; o[2] = q[2];
        o[3] = q[0]; o[4] = q[2]; o[5] = q[3];
    }
}

/* Client arrays, glDrawElements. */
static void box_client(float x0, float y0, float z0, float x1, float y1, float z1) {
    float v[8][3];
    GLushort idx[36];
    box_arrays(x0, y0, z0, x1, y1, z1, v, idx);
    if (glsl_mvp) use_program(glsl_mvp);
    if (glsl_mvp && generic_vertex) {
        attrib_pointer(0, 3, GL_FLOAT, GL_FALSE, 0, v);
        enable_attrib(0);
        glDrawElements(GL_TRIANGLES, 36, GL_UNSIGNED_SHORT, idx);
        disable_attrib(0);
    } else {
        glEnableClientState(GL_VERTEX_ARRAY);
        glVertexPointer(3, GL_FLOAT, 0, v);
        glDrawElements(GL_TRIANGLES, 36, GL_UNSIGNED_SHORT, idx);
        glDisableClientState(GL_VERTEX_ARRAY);
    }
    if (glsl_mvp) use_program(0);
}

/* A buffer object for vertices and indices, glDrawRangeElements; the z1 corners
 * are rewritten with glBufferSubData after the first upload. */
static void box_buffer(float x0, float y0, float z0, float x1, float y1, float z1) {
    static GLuint bufs[2];
    float v[8][3];
    GLushort idx[36];
    if (!bufs[0]) gen_buffers(2, bufs);
    box_arrays(x0, y0, z0, x1, y1, z0 + 1.0f, v, idx);
    bind_buffer(GL_ARRAY_BUFFER, bufs[0]);
    buffer_data(GL_ARRAY_BUFFER, sizeof v, v, GL_STREAM_DRAW);
    for (int i = 4; i < 8; ++i) v[i][2] = z1;
    buffer_sub_data(GL_ARRAY_BUFFER, 4 * sizeof v[0], 4 * sizeof v[0], v[4]);
    bind_buffer(GL_ELEMENT_ARRAY_BUFFER, bufs[1]);
    buffer_data(GL_ELEMENT_ARRAY_BUFFER, sizeof idx, idx, GL_STREAM_DRAW);
    glEnableClientState(GL_VERTEX_ARRAY);
    glVertexPointer(3, GL_FLOAT, 0, (const void*)0);
    if (glsl_ftransform) use_program(glsl_ftransform);
    glDrawRangeElements(GL_TRIANGLES, 0, 7, 36, GL_UNSIGNED_SHORT, (const void*)0);
    if (glsl_ftransform) use_program(0);
    glDisableClientState(GL_VERTEX_ARRAY);
    bind_buffer(GL_ARRAY_BUFFER, 0);
    bind_buffer(GL_ELEMENT_ARRAY_BUFFER, 0);
}

/* Immediate mode, quads. */
static void box_immediate(float x0, float y0, float z0, float x1, float y1, float z1) {
    float v[8][3];
    GLushort idx[36];
    box_arrays(x0, y0, z0, x1, y1, z1, v, idx);
    glBegin(GL_TRIANGLES);
    for (int i = 0; i < 36; ++i) glVertex3fv(v[idx[i]]);
    glEnd();
}

/* A unit sphere as quad strips (immediate mode), outward counter-clockwise. */
static void sphere_immediate(int slices, int stacks) {
    for (int j = 0; j < stacks; ++j) {
        const double a0 = M_PI * (-0.5 + (double)j / stacks), a1 = M_PI * (-0.5 + (double)(j + 1) / stacks);
        glBegin(GL_QUAD_STRIP);
        for (int i = 0; i <= slices; ++i) {
            const double b = 2.0 * M_PI * i / slices;
            glVertex3d(cos(a1) * cos(b), cos(a1) * sin(b), sin(a1));
            glVertex3d(cos(a0) * cos(b), cos(a0) * sin(b), sin(a0));
        }
        glEnd();
    }
}

/* A floor quad of the scene that is not collisionable, drawn with glDrawArrays. */
static void floor_quad(float x0, float y0, float x1, float y1, float z) {
    const float v[4][3] = {{x0, y0, z}, {x1, y0, z}, {x1, y1, z}, {x0, y1, z}};
    glEnableClientState(GL_VERTEX_ARRAY);
    glVertexPointer(3, GL_FLOAT, 0, v);
    if (glsl_mvp) use_program(glsl_mvp);
    glDrawArrays(GL_TRIANGLE_FAN, 0, 4);
    if (glsl_mvp) use_program(0);
    glDisableClientState(GL_VERTEX_ARRAY);
}

static void overlay(int w, int h) {
    glMatrixMode(GL_PROJECTION);
    glLoadIdentity();
    glOrtho(0, w, 0, h, -1, 1);
    glMatrixMode(GL_MODELVIEW);
    glLoadIdentity();
    glDisable(GL_DEPTH_TEST);
    glRectf(0, 0, 8, 4);   /* a 2D overlay: 32 fragments of GPU work */
    glEnable(GL_DEPTH_TEST);
}

static void frame_ortho(int w, int h, int frame) {
    glViewport(0, 0, w, h);
    glMatrixMode(GL_PROJECTION);
    glLoadIdentity();
    glOrtho(0, w, 0, h, -100, 100);   /* eye z in [-100, 100]; pixel (x, y) from the bottom */
    glMatrixMode(GL_MODELVIEW);
    glLoadIdentity();
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    if (frame == 0) {
        /* A and B overlap in x, y and z: one pair. C is apart. */
        begin_object(1); box_client(8, 8, -20, 28, 28, -10); end_object();
        begin_object(2); box_buffer(20, 16, -15, 40, 36, -5); end_object();
        push_marker(0, "rbcd-object 3"); box_immediate(60, 8, -20, 70, 18, -10); pop_marker();
    } else {
        /* B inside A: one pair, by containment. C apart, drawn twice (a second
         * pass with GL_EQUAL that is not a new collisionable surface). */
        begin_object(1); box_client(8, 8, -40, 48, 48, -4); end_object();
        begin_object(2); box_buffer(20, 20, -30, 30, 30, -20); end_object();
        push_marker(0, "rbcd-object 3"); box_immediate(60, 8, -20, 70, 18, -10); pop_marker();
        glDepthFunc(GL_EQUAL);
        glDepthMask(GL_FALSE);
        push_marker(0, "rbcd-object 3"); box_immediate(60, 8, -20, 70, 18, -10); pop_marker();
        glDepthMask(GL_TRUE);
        glDepthFunc(GL_LESS);
        inject_fault();
    }
    floor_quad(80, 40, 120, 80, -50);   /* 40 x 40 = 1600 fragments, not collisionable */
    overlay(w, h);
}

/* A GLSL 1.20 program of the one vertex shader `main` (the driver's own
 * fragment stage: fixed-function colour). */
static GLuint glsl_program(const char* main) {
    const GLuint sh = create_shader(GL_VERTEX_SHADER), prog = create_program();
    const char* src[2] = {"#version 120\n", main};
    shader_source(sh, 2, src, NULL);
    compile_shader(sh);
    attach_shader(prog, sh);
    link_program(prog);
    return prog;
}

static void frame_perspective(int w, int h) {
    generic_vertex = 1;
    glViewport(0, 0, w, h);
    glMatrixMode(GL_PROJECTION);
    glLoadIdentity();
    glFrustum(-1.0 * w / h, 1.0 * w / h, -1, 1, 2, 50);
    glMatrixMode(GL_MODELVIEW);
    glLoadIdentity();
    glTranslatef(0, 0, -10);
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    /* The sphere (radius 1.5 at x = -1) and a box reaching x = -0.2 overlap;
     * the second box (x from 2) is apart from both. */
    glPushMatrix();
    glTranslatef(-1, 0, 0);
    glRotatef(30, 0, 1, 0);
    glScalef(1.5f, 1.5f, 1.5f);
    begin_object(4); sphere_immediate(24, 12); end_object();
    glPopMatrix();
    glPushMatrix();
    glRotatef(20, 0, 0, 1);
    begin_object(1); box_client(-0.6f, -0.5f, -0.5f, 0.6f, 0.5f, 0.5f); end_object();
    glPopMatrix();
    begin_object(2); box_buffer(2, -1, -1, 3.5f, 1, 1); end_object();
    overlay(w, h);
    generic_vertex = 0;
}

int main(int argc, char** argv) {
    const int w = argc > 2 ? atoi(argv[1]) : 128, h = argc > 2 ? atoi(argv[2]) : 96;
    if (argc > 3) fault = argv[3];
    Display* dpy = XOpenDisplay(NULL);
    if (!dpy) {
        fprintf(stderr, "gl_boxes: cannot open display (run under Xvfb)\n");
        return 1;
    }
    int attrs[] = {GLX_RGBA, GLX_DOUBLEBUFFER, GLX_DEPTH_SIZE, 24, None};
    XVisualInfo* vi = glXChooseVisual(dpy, DefaultScreen(dpy), attrs);
    if (!vi) {
        fprintf(stderr, "gl_boxes: no visual with a 24-bit depth buffer\n");
        return 1;
    }
    XSetWindowAttributes swa;
    memset(&swa, 0, sizeof swa);
    swa.colormap = XCreateColormap(dpy, RootWindow(dpy, vi->screen), vi->visual, AllocNone);
    swa.event_mask = StructureNotifyMask;
    Window win = XCreateWindow(dpy, RootWindow(dpy, vi->screen), 0, 0, w, h, 0, vi->depth, InputOutput, vi->visual,
                               CWColormap | CWEventMask, &swa);
    XMapWindow(dpy, win);
    for (XEvent ev;;) {   /* render only once the window is on the screen, at its size */
        XNextEvent(dpy, &ev);
        if (ev.type == MapNotify) break;
    }
    GLXContext ctx = glXCreateContext(dpy, vi, NULL, True);
    const int read_other = !strcmp(fault, "readother");
    Window other = 0;
    if (read_other) {
        other = XCreateWindow(dpy, RootWindow(dpy, vi->screen), 0, 0, 16, 16, 0, vi->depth, InputOutput,
                              vi->visual, CWColormap | CWEventMask, &swa);
        XMapWindow(dpy, other);
        for (XEvent ev;;) {
            XNextEvent(dpy, &ev);
            if (ev.type == MapNotify) break;
        }
        glXMakeContextCurrent(dpy, win, other, ctx);
    } else {
        glXMakeCurrent(dpy, win, ctx);
    }
    push_group = (PFNGLPUSHDEBUGGROUPPROC)glXGetProcAddress((const GLubyte*)"glPushDebugGroup");
    pop_group = (PFNGLPOPDEBUGGROUPPROC)glXGetProcAddress((const GLubyte*)"glPopDebugGroup");
    push_marker = (PFNGLPUSHGROUPMARKEREXTPROC)glXGetProcAddress((const GLubyte*)"glPushGroupMarkerEXT");
    pop_marker = (PFNGLPOPGROUPMARKEREXTPROC)glXGetProcAddress((const GLubyte*)"glPopGroupMarkerEXT");
    gen_buffers = (PFNGLGENBUFFERSPROC)glXGetProcAddress((const GLubyte*)"glGenBuffers");
    bind_buffer = (PFNGLBINDBUFFERPROC)glXGetProcAddress((const GLubyte*)"glBindBuffer");
    buffer_data = (PFNGLBUFFERDATAPROC)glXGetProcAddress((const GLubyte*)"glBufferData");
    buffer_sub_data = (PFNGLBUFFERSUBDATAPROC)glXGetProcAddress((const GLubyte*)"glBufferSubData");
    create_shader = (PFNGLCREATESHADERPROC)glXGetProcAddress((const GLubyte*)"glCreateShader");
    shader_source = (PFNGLSHADERSOURCEPROC)glXGetProcAddress((const GLubyte*)"glShaderSource");
    compile_shader = (PFNGLCOMPILESHADERPROC)glXGetProcAddress((const GLubyte*)"glCompileShader");
    create_program = (PFNGLCREATEPROGRAMPROC)glXGetProcAddress((const GLubyte*)"glCreateProgram");
    attach_shader = (PFNGLATTACHSHADERPROC)glXGetProcAddress((const GLubyte*)"glAttachShader");
    link_program = (PFNGLLINKPROGRAMPROC)glXGetProcAddress((const GLubyte*)"glLinkProgram");
    use_program = (PFNGLUSEPROGRAMPROC)glXGetProcAddress((const GLubyte*)"glUseProgram");
    attrib_pointer = (PFNGLVERTEXATTRIBPOINTERPROC)glXGetProcAddress((const GLubyte*)"glVertexAttribPointer");
    enable_attrib = (PFNGLENABLEVERTEXATTRIBARRAYPROC)glXGetProcAddress((const GLubyte*)"glEnableVertexAttribArray");
    disable_attrib =
        (PFNGLDISABLEVERTEXATTRIBARRAYPROC)glXGetProcAddress((const GLubyte*)"glDisableVertexAttribArray");
    if (!push_group || !pop_group || !push_marker || !pop_marker || !gen_buffers) {
        fprintf(stderr, "gl_boxes: the GL lacks KHR_debug, EXT_debug_marker or buffer objects\n");
        return 1;
    }
    if (!strcmp(fault, "glsl")) {
        glsl_mvp = glsl_program("void main() { gl_Position = gl_ModelViewProjectionMatrix * gl_Vertex; }\n");
        glsl_ftransform = glsl_program("void main() { gl_Position = ftransform(); }\n");
    }
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_LESS);
    glEnable(GL_CULL_FACE);
    glCullFace(GL_BACK);
    glFrontFace(GL_CCW);
    for (int frame = 0; frame < 3; ++frame) {
        if (frame < 2) {
            frame_ortho(w, h, frame);
        } else {
            if (read_other) glXMakeContextCurrent(dpy, win, win, ctx);
            frame_perspective(w, h);
        }
        glXSwapBuffers(dpy, win);
    }
    glXMakeCurrent(dpy, None, NULL);
    glXDestroyContext(dpy, ctx);
    XCloseDisplay(dpy);
    return 0;
}

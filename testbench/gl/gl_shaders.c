/* A small OpenGL 3.3 core program of the project's own, drawn with shaders:
 * captured under Xvfb with `apitrace trace` and converted by rbcd-gl2rbt in
 * the tests (testbench/gl/test_gl2rbt_shaders.py), whose docstring gives what
 * each frame must become, worked out by hand.
 *
 *   gl_shaders [WIDTH HEIGHT [FAULT]]   (default 128 96; the window is the screen)
 *
 * FAULT adds, in frame 1, one draw the converter must convert as Mesa
 * draws it: geometry (a program whose geometry shader moves the triangle
 * below by the texture fault's texel, its vertex shader passing positions
 * through: the same fragments), compile (a program
 * whose vertex shader does not compile, used all the same:
 * GL_INVALID_OPERATION, the draw runs the program in use), texture (a vertex
 * shader that samples a 2D texture uploaded with glTexImage2D: the triangle
 * (0,0,1) (1,0,1) (1,1,1) moved by texel (0, 0) to clip space (-0.75, -0.5,
 * -0.5) (0.25, -0.5, -0.5) (0.25, 0.5, -0.5), in front of every box, object
 * 9), rendered (the same triangle and vertex shader, its 2x2 texture
 * rendered instead by a draw into a framebuffer object whose fragment shader
 * writes texel (0, 0)'s value everywhere: the same fragments), cube (the
 * same triangle moved by a texel of a cube map, every face that texel),
 * cubeseam (the cube map filtered linearly near the +X face's edge with +Y,
 * whose texel differs, GL_TEXTURE_CUBE_MAP_SEAMLESS enabled), array
 * (the same, by layer 1 of a 2D array texture whose layer 0 is another),
 * image (that layer read by imageLoad through image unit 3, bound with
 * glBindImageTexture as a 2D image, the texture bound at no texture unit),
 * multisample (sample 3 of a 4-sample texture, the only one a draw under
 * a sample mask writes the texel into, the others cleared to another),
 * default (the default 3D texture, name 0, given the texel everywhere),
 * msimage (the multisample fault's sample 3 read by imageLoad through
 * image unit 3), msdepth (sample 3 of a 4-sample DEPTH_COMPONENT32F
 * texture a draw fills with depth 0.5, swizzled so that green reads the
 * depth and red zero: the triangle moved by the texel times green),
 * separable (the "texture" fault's draw through a program pipeline: its
 * vertex shader a separable program, its fragment shader one made by
 * glCreateShaderProgramv, no program in use, the sampler set with
 * glProgramUniform1i: the same fragments).
 *
 * One program: a std140 uniform block Matrices {proj, view} at binding 2, a
 * uniform mat4 model, the position attribute bound with glBindAttribLocation
 * and a per-instance offset at an explicit location (divisor 1, or a constant
 * attribute value when its array is disabled). Geometry comes through every
 * path the shader path takes: indexed and base-vertex draws from vertex array
 * objects sharing one buffer, an instanced draw whose instances are two
 * objects, a floor of GL_SHORT positions written through glMapBufferRange,
 * triangle strips cut by primitive restart, glDrawRangeElements, uniform
 * block contents changed with glBufferSubData, and a depth-only pass into a
 * framebuffer object that is not the camera pass; box 1 of frame 1 is drawn
 * by a second program whose fragment shader can discard and writes
 * gl_FragDepth (without changing a fragment). Collisionable objects are
 * tagged with KHR_debug groups "rbcd-object" (id = object; an instanced draw's
 * instance i is object id + i). */
#define GL_GLEXT_PROTOTYPES 1
#include <GL/gl.h>
#include <GL/glext.h>
#include <GL/glx.h>
#include <GL/glxext.h>
#include <X11/Xlib.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "unit_cube.h"

static const char* vertex_source =
    "#version 330 core\n"
    "layout(std140) uniform Matrices { mat4 proj; mat4 view; };\n"
    "uniform mat4 model;\n"
    "in vec3 position;\n"
    "layout(location = 3) in vec3 offset;\n"
    "void main() { gl_Position = proj * view * (model * vec4(position, 1.0) + vec4(offset, 0.0)); }\n";
static const char* fragment_source =
    "#version 330 core\n"
    "out vec4 colour;\n"
    "void main() { colour = vec4(gl_FragCoord.z); }\n";
/* A fragment shader that can discard and writes gl_FragDepth, though it
 * changes no fragment: box 1 of frame 1 is drawn with it. */
static const char* effects_source =
    "#version 330 core\n"
    "out vec4 colour;\n"
    "void main() { if (gl_FragCoord.z > 2.0) discard; gl_FragDepth = gl_FragCoord.z; colour = vec4(1.0); }\n";

/* The "texture" and "separable" faults' texels: (0, 0) moves the triangle. */
static const float height_texels[2][2][4] = {{{-0.75f, -0.5f, -1.5f, 0}, {9, 9, 9, 0}}, {{-9, -9, 9, 0}, {5, 5, 5, 0}}};

static GLushort triangles[36], strips[29];
static GLint model_at;
static const char* fault = "";

/* The "geometry" fault: the triangle moved by the texel in the geometry
 * stage, its vertex shader passing the position through. */
static const char* geometry_source =
    "#version 330 core\n"
    "layout(triangles) in; layout(triangle_strip, max_vertices = 3) out;\n"
    "void main() {\n"
    "    for (int i = 0; i < 3; ++i) { gl_Position = gl_in[i].gl_Position + vec4(-0.75, -0.5, -1.5, 0.0); EmitVertex(); }\n"
    "}\n";
static const char* passing_source =
    "#version 330 core\n"
    "in vec3 position;\n"
    "void main() { gl_Position = vec4(position, 1.0); }\n";
static const char* texture_source =
    "#version 330 core\n"
    "uniform sampler2D heights;\n"
    "in vec3 position;\n"
    "void main() { gl_Position = vec4(position, 1.0) + textureLod(heights, position.xy, 0.0); }\n";
static const char* cube_source =
    "#version 330 core\n"
    "uniform samplerCube heights;\n"
    "in vec3 position;\n"
    "void main() { gl_Position = vec4(position, 1.0) + textureLod(heights, vec3(1.0, 0.2, -0.3), 0.0); }\n";
/* Near the +X face's edge with +Y (face coordinates s 0.5, t 0.25): with
 * GL_LINEAR and seamless cube maps a quarter of +Y's texel. */
static const char* cubeseam_source =
    "#version 330 core\n"
    "uniform samplerCube heights;\n"
    "in vec3 position;\n"
    "void main() { gl_Position = vec4(position, 1.0) + textureLod(heights, vec3(1.0, 0.5, 0.0), 0.0); }\n";
static const char* array_source =
    "#version 330 core\n"
    "uniform sampler2DArray heights;\n"
    "in vec3 position;\n"
    "void main() { gl_Position = vec4(position, 1.0) + textureLod(heights, vec3(position.xy, 1.0), 0.0); }\n";
static const char* default_source =
    "#version 330 core\n"
    "uniform sampler3D heights;\n"
    "in vec3 position;\n"
    "void main() { gl_Position = vec4(position, 1.0) + textureLod(heights, vec3(0.25), 0.0); }\n";
static const char* multisample_source =
    "#version 330 core\n"
    "uniform sampler2DMS heights;\n"
    "in vec3 position;\n"
    "void main() { gl_Position = vec4(position, 1.0) + texelFetch(heights, ivec2(0, 0), 3); }\n";
static const char* msimage_source =
    "#version 420 core\n"
    "layout(rgba32f) readonly uniform image2DMS heights;\n"
    "in vec3 position;\n"
    "void main() { gl_Position = vec4(position, 1.0) + imageLoad(heights, ivec2(0, 0), 3); }\n";
static const char* msdepth_source =
    "#version 330 core\n"
    "uniform sampler2DMS heights;\n"
    "in vec3 position;\n"
    "void main() {\n"
    "    float d = texelFetch(heights, ivec2(0, 0), 3).g;\n"
    "    gl_Position = vec4(position, 1.0) + vec4(-1.5, -1.0, -3.0, 0.0) * d;\n"
    "}\n";
static const char* image_source =
    "#version 420 core\n"
    "layout(rgba32f) readonly uniform image2D heights;\n"
    "in vec3 position;\n"
    "void main() { gl_Position = vec4(position, 1.0) + imageLoad(heights, ivec2(0, 0)); }\n";
/* The "rendered" fault's fill: one triangle over the whole 2x2 target from
 * the cube's vertices 4 to 6, (0,0) (1,0) (1,1) to clip (-1,-1) (3,-1)
 * (-1,3), every texel the "texture" fault's texel (0, 0). */
static const char* fill_vertex_source =
    "#version 330 core\n"
    "in vec3 position;\n"
    "void main() { gl_Position = vec4(4.0 * (position.x - position.y) - 1.0, 4.0 * position.y - 1.0, 0.0, 1.0); }\n";
static const char* fill_fragment_source =
    "#version 330 core\n"
    "out vec4 colour;\n"
    "void main() { colour = vec4(-0.75, -0.5, -1.5, 0.0); }\n";
static const char* broken_source =
    "#version 330 core\n"
    "in vec3 position;\n"
    "void main() { gl_Position = vec4(position, 1.0) }\n";

static void matrix_box(float* m, float x0, float y0, float z0, float x1, float y1, float z1) {
    memset(m, 0, 16 * sizeof *m);   /* column-major: scale to the box, then move to its corner */
    m[0] = x1 - x0, m[5] = y1 - y0, m[10] = z1 - z0, m[15] = 1;
    m[12] = x0, m[13] = y0, m[14] = z0;
}

static void model(float x0, float y0, float z0, float x1, float y1, float z1) {
    float m[16];
    matrix_box(m, x0, y0, z0, x1, y1, z1);
    glUniformMatrix4fv(model_at, 1, GL_FALSE, m);
}

static void begin_object(unsigned id) { glPushDebugGroup(GL_DEBUG_SOURCE_APPLICATION, id, -1, "rbcd-object"); }
static void end_object(void) { glPopDebugGroup(); }

static GLuint compile(GLenum kind, const char* text) {
    GLuint s = glCreateShader(kind);
    glShaderSource(s, 1, &text, NULL);
    glCompileShader(s);
    GLint ok = 0;
    glGetShaderiv(s, GL_COMPILE_STATUS, &ok);
    if (!ok && text != broken_source) {
        char log[1024];
        glGetShaderInfoLog(s, sizeof log, NULL, log);
        fprintf(stderr, "gl_shaders: shader does not compile: %s\n", log);
        exit(1);
    }
    return s;
}

/* A 2x2 RGBA32F texture on unit 2 (where the faults' vertex shaders read),
 * nearest filtering, its texels `texels` (NULL: none given). */
static GLuint texture_2x2(const void* texels) {
    GLuint tex;
    glActiveTexture(GL_TEXTURE2);
    glGenTextures(1, &tex);
    glBindTexture(GL_TEXTURE_2D, tex);
    glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA32F, 2, 2, 0, GL_RGBA, GL_FLOAT, texels);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    glActiveTexture(GL_TEXTURE0);
    return tex;
}

/* Texture `tex` (of `target`, 2x2) filled by a draw into a framebuffer
 * object: every texel the "texture" fault's texel (0, 0); with `mask`, only
 * the samples it names, the others cleared to (9, 9, 9, 0) first. */
static void fill(GLenum target, GLuint tex, GLuint mask) {
    static const float other[4] = {9, 9, 9, 0}, far_depth = 1.0f;
    GLuint fb, program = glCreateProgram();
    GLint viewport[4], depth_size = 0;
    glGetIntegerv(GL_VIEWPORT, viewport);
    glGenFramebuffers(1, &fb);
    glBindFramebuffer(GL_FRAMEBUFFER, fb);
    glBindTexture(target, tex);
    glGetTexLevelParameteriv(target, 0, GL_TEXTURE_DEPTH_SIZE, &depth_size);
    glBindTexture(target, 0);
    if (depth_size) {   /* a depth texture: the triangle's depth, 0.5 */
        glFramebufferTexture2D(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, target, tex, 0);
        glDrawBuffer(GL_NONE);
        glClearBufferfv(GL_DEPTH, 0, &far_depth);
    } else {
        glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, target, tex, 0);
    }
    glAttachShader(program, compile(GL_VERTEX_SHADER, fill_vertex_source));
    glAttachShader(program, compile(GL_FRAGMENT_SHADER, fill_fragment_source));
    glBindAttribLocation(program, 0, "position");
    glLinkProgram(program);
    glUseProgram(program);
    glViewport(0, 0, 2, 2);
    if (mask) {
        glClearBufferfv(GL_COLOR, 0, other);
        glEnable(GL_SAMPLE_MASK);
        glSampleMaski(0, mask);
    }
    glDrawArrays(GL_TRIANGLES, 4, 3);
    glDisable(GL_SAMPLE_MASK);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    glViewport(viewport[0], viewport[1], viewport[2], viewport[3]);
}

/* The one fault draw of frame 1 (see the header comment): a small
 * triangle through a program of its own. */
static void inject_fault(GLuint main_program) {
    if (!*fault) return;
    GLuint p = glCreateProgram();
    if (!strcmp(fault, "geometry")) {
        glAttachShader(p, compile(GL_VERTEX_SHADER, passing_source));
        glAttachShader(p, compile(GL_GEOMETRY_SHADER, geometry_source));
    } else if (!strcmp(fault, "rendered")) {
        fill(GL_TEXTURE_2D, texture_2x2(NULL), 0);
        glAttachShader(p, compile(GL_VERTEX_SHADER, texture_source));
    } else if (!strcmp(fault, "default")) {
        float texels[2][2][2][4];   /* the default 3D texture (name 0), every texel the texel */
        for (int i = 0; i < 8; ++i) memcpy(((float(*)[4])texels)[i], height_texels[0][0], sizeof height_texels[0][0]);
        glActiveTexture(GL_TEXTURE2);
        glBindTexture(GL_TEXTURE_3D, 0);
        glTexImage3D(GL_TEXTURE_3D, 0, GL_RGBA32F, 2, 2, 2, 0, GL_RGBA, GL_FLOAT, texels);
        glTexParameteri(GL_TEXTURE_3D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
        glActiveTexture(GL_TEXTURE0);
        glAttachShader(p, compile(GL_VERTEX_SHADER, default_source));
    } else if (!strcmp(fault, "multisample")) {
        GLuint tex;
        glActiveTexture(GL_TEXTURE2);
        glGenTextures(1, &tex);
        glBindTexture(GL_TEXTURE_2D_MULTISAMPLE, tex);
        glTexImage2DMultisample(GL_TEXTURE_2D_MULTISAMPLE, 4, GL_RGBA32F, 2, 2, GL_TRUE);
        glActiveTexture(GL_TEXTURE0);
        fill(GL_TEXTURE_2D_MULTISAMPLE, tex, 1u << 3);
        glAttachShader(p, compile(GL_VERTEX_SHADER, multisample_source));
    } else if (!strcmp(fault, "msdepth")) {
        GLuint tex;
        glActiveTexture(GL_TEXTURE2);
        glGenTextures(1, &tex);
        glBindTexture(GL_TEXTURE_2D_MULTISAMPLE, tex);
        glTexImage2DMultisample(GL_TEXTURE_2D_MULTISAMPLE, 4, GL_DEPTH_COMPONENT32F, 2, 2, GL_TRUE);
        glTexParameteri(GL_TEXTURE_2D_MULTISAMPLE, GL_TEXTURE_SWIZZLE_R, GL_ZERO);
        glTexParameteri(GL_TEXTURE_2D_MULTISAMPLE, GL_TEXTURE_SWIZZLE_G, GL_RED);
        glActiveTexture(GL_TEXTURE0);
        fill(GL_TEXTURE_2D_MULTISAMPLE, tex, 0);
        glAttachShader(p, compile(GL_VERTEX_SHADER, msdepth_source));
    } else if (!strcmp(fault, "msimage")) {
        GLuint tex;
        glGenTextures(1, &tex);
        glBindTexture(GL_TEXTURE_2D_MULTISAMPLE, tex);
        glTexImage2DMultisample(GL_TEXTURE_2D_MULTISAMPLE, 4, GL_RGBA32F, 2, 2, GL_TRUE);
        glBindTexture(GL_TEXTURE_2D_MULTISAMPLE, 0);
        fill(GL_TEXTURE_2D_MULTISAMPLE, tex, 1u << 3);
        glBindImageTexture(3, tex, 0, GL_FALSE, 0, GL_READ_ONLY, GL_RGBA32F);
        glAttachShader(p, compile(GL_VERTEX_SHADER, msimage_source));
    } else if (!strcmp(fault, "cube") || !strcmp(fault, "array") || !strcmp(fault, "image") ||
               !strcmp(fault, "cubeseam")) {
        static const float texel[4] = {-0.75f, -0.5f, -1.5f, 0}, other[4] = {9, 9, 9, 0};
        static const float above[4] = {-0.25f, -0.5f, -1.5f, 0};   /* cubeseam's +Y face */
        const int seam = !strcmp(fault, "cubeseam");
        const int cube = !strcmp(fault, "cube") || seam;
        const GLenum target = cube ? GL_TEXTURE_CUBE_MAP : GL_TEXTURE_2D_ARRAY;
        GLuint tex;
        glActiveTexture(GL_TEXTURE2);
        glGenTextures(1, &tex);
        glBindTexture(target, tex);
        if (cube) {
            for (GLenum face = 0; face < 6; ++face)
                glTexImage2D(GL_TEXTURE_CUBE_MAP_POSITIVE_X + face, 0, GL_RGBA32F, 1, 1, 0, GL_RGBA, GL_FLOAT,
                             seam && face == 2 ? above : texel);
        } else {
            float layers[2][2][2][4];   /* layer 0: another texel everywhere; layer 1: the texel */
            for (int y = 0; y < 2; ++y)
                for (int x = 0; x < 2; ++x) {
                    memcpy(layers[0][y][x], other, sizeof other);
                    memcpy(layers[1][y][x], texel, sizeof texel);
                }
            glTexImage3D(GL_TEXTURE_2D_ARRAY, 0, GL_RGBA32F, 2, 2, 2, 0, GL_RGBA, GL_FLOAT, layers);
        }
        glTexParameteri(target, GL_TEXTURE_MIN_FILTER, seam ? GL_LINEAR : GL_NEAREST);
        glTexParameteri(target, GL_TEXTURE_MAG_FILTER, seam ? GL_LINEAR : GL_NEAREST);
        if (seam) glEnable(GL_TEXTURE_CUBE_MAP_SEAMLESS);
        glActiveTexture(GL_TEXTURE0);
        if (!strcmp(fault, "image")) {
            glBindTexture(target, 0);   /* read through image unit 3 alone: layer 1 as a 2D image */
            glBindImageTexture(3, tex, 0, GL_FALSE, 1, GL_READ_ONLY, GL_RGBA32F);
            glAttachShader(p, compile(GL_VERTEX_SHADER, image_source));
        } else {
            glAttachShader(p, compile(GL_VERTEX_SHADER, seam ? cubeseam_source : cube ? cube_source : array_source));
        }
    } else if (!strcmp(fault, "texture") || !strcmp(fault, "separable")) {
        texture_2x2(height_texels);
        if (!strcmp(fault, "separable")) glProgramParameteri(p, GL_PROGRAM_SEPARABLE, GL_TRUE);
        glAttachShader(p, compile(GL_VERTEX_SHADER, texture_source));
    } else if (!strcmp(fault, "compile")) {
        glAttachShader(p, compile(GL_VERTEX_SHADER, broken_source));
    }
    glBindAttribLocation(p, 0, "position");
    glLinkProgram(p);
    GLuint pipeline = 0;
    if (!strcmp(fault, "separable")) {
        GLuint fragment = glCreateShaderProgramv(GL_FRAGMENT_SHADER, 1, &fragment_source);
        glGenProgramPipelines(1, &pipeline);
        glUseProgramStages(pipeline, GL_VERTEX_SHADER_BIT, p);
        glUseProgramStages(pipeline, GL_FRAGMENT_SHADER_BIT, fragment);
        glUseProgram(0);
        glBindProgramPipeline(pipeline);
        glProgramUniform1i(p, glGetUniformLocation(p, "heights"), 2);
    } else {
        glUseProgram(p);
    }
    const int textured = !strcmp(fault, "texture") || !strcmp(fault, "rendered") || !strcmp(fault, "cube") ||
                         !strcmp(fault, "cubeseam") ||
                         !strcmp(fault, "array") || !strcmp(fault, "image") || !strcmp(fault, "multisample") ||
                         !strcmp(fault, "default") || !strcmp(fault, "msimage") || !strcmp(fault, "msdepth") ||
                         !strcmp(fault, "geometry") || pipeline;
    if (textured) {
        if (!pipeline && strcmp(fault, "geometry"))
            glUniform1i(glGetUniformLocation(p, "heights"), !strcmp(fault, "image") || !strcmp(fault, "msimage") ? 3 : 2);
        begin_object(9);
    }
    glDrawArrays(GL_TRIANGLES, textured ? 4 : 0, 3);   /* the cube's first face from vertex 4 */
    if (textured) end_object();
    if (pipeline) glBindProgramPipeline(0);
    glUseProgram(main_program);
}

/* Orthographic (0, w, 0, h, -100, 100): window depth 0.5 - z / 200. */
static void ortho(float* m, float w, float h) {
    memset(m, 0, 16 * sizeof *m);
    m[0] = 2 / w, m[5] = 2 / h, m[10] = -0.01f, m[15] = 1;
    m[12] = -1, m[13] = -1;
}

int main(int argc, char** argv) {
    const int w = argc > 2 ? atoi(argv[1]) : 128, h = argc > 2 ? atoi(argv[2]) : 96;
    if (argc > 3) fault = argv[3];
    Display* dpy = XOpenDisplay(NULL);
    if (!dpy) {
        fprintf(stderr, "gl_shaders: cannot open display (run under Xvfb)\n");
        return 1;
    }
    int fb_attrs[] = {GLX_RENDER_TYPE, GLX_RGBA_BIT, GLX_DOUBLEBUFFER, True, GLX_DEPTH_SIZE, 24, None};
    int count = 0;
    GLXFBConfig* configs = glXChooseFBConfig(dpy, DefaultScreen(dpy), fb_attrs, &count);
    if (!configs || count == 0) {
        fprintf(stderr, "gl_shaders: no framebuffer configuration with a 24-bit depth buffer\n");
        return 1;
    }
    XVisualInfo* vi = glXGetVisualFromFBConfig(dpy, configs[0]);
    XSetWindowAttributes swa;
    memset(&swa, 0, sizeof swa);
    swa.colormap = XCreateColormap(dpy, RootWindow(dpy, vi->screen), vi->visual, AllocNone);
    swa.event_mask = StructureNotifyMask;
    Window win = XCreateWindow(dpy, RootWindow(dpy, vi->screen), 0, 0, w, h, 0, vi->depth, InputOutput, vi->visual,
                               CWColormap | CWEventMask, &swa);
    XMapWindow(dpy, win);
    for (XEvent ev;;) {
        XNextEvent(dpy, &ev);
        if (ev.type == MapNotify) break;
    }
    PFNGLXCREATECONTEXTATTRIBSARBPROC create_context =
        (PFNGLXCREATECONTEXTATTRIBSARBPROC)glXGetProcAddress((const GLubyte*)"glXCreateContextAttribsARB");
    int ctx_attrs[] = {GLX_CONTEXT_MAJOR_VERSION_ARB, 3, GLX_CONTEXT_MINOR_VERSION_ARB, 3,
                       GLX_CONTEXT_PROFILE_MASK_ARB, GLX_CONTEXT_CORE_PROFILE_BIT_ARB, None};
    GLXContext ctx = create_context ? create_context(dpy, configs[0], NULL, True, ctx_attrs) : NULL;
    if (!ctx) {
        fprintf(stderr, "gl_shaders: no OpenGL 3.3 core context\n");
        return 1;
    }
    glXMakeCurrent(dpy, win, ctx);

    GLuint prog = glCreateProgram();
    glAttachShader(prog, compile(GL_VERTEX_SHADER, vertex_source));
    glAttachShader(prog, compile(GL_FRAGMENT_SHADER, fragment_source));
    glBindAttribLocation(prog, 0, "position");
    glBindFragDataLocation(prog, 0, "colour");
    glLinkProgram(prog);
    GLint ok = 0;
    glGetProgramiv(prog, GL_LINK_STATUS, &ok);
    if (!ok) {
        fprintf(stderr, "gl_shaders: the program does not link\n");
        return 1;
    }
    GLuint effects = glCreateProgram();
    glAttachShader(effects, compile(GL_VERTEX_SHADER, vertex_source));
    glAttachShader(effects, compile(GL_FRAGMENT_SHADER, effects_source));
    glBindAttribLocation(effects, 0, "position");
    glLinkProgram(effects);
    glUniformBlockBinding(effects, glGetUniformBlockIndex(effects, "Matrices"), 2);
    const GLint effects_model_at = glGetUniformLocation(effects, "model");
    glUseProgram(prog);
    model_at = glGetUniformLocation(prog, "model");
    glUniformBlockBinding(prog, glGetUniformBlockIndex(prog, "Matrices"), 2);

    /* Matrices at binding 2: proj, then view (identity). */
    float matrices[32];
    ortho(matrices, (float)w, (float)h);
    memset(matrices + 16, 0, 16 * sizeof(float));
    matrices[16] = matrices[21] = matrices[26] = matrices[31] = 1;
    GLuint buffers[5];
    glGenBuffers(5, buffers);
    const GLuint ubo = buffers[0], vbo = buffers[1], ibo = buffers[2], floor_vbo = buffers[3], inst = buffers[4];
    glBindBuffer(GL_UNIFORM_BUFFER, ubo);
    glBufferData(GL_UNIFORM_BUFFER, sizeof matrices, matrices, GL_DYNAMIC_DRAW);
    glBindBufferBase(GL_UNIFORM_BUFFER, 2, ubo);

    /* One vertex buffer: four padding vertices, then the cube (a base vertex of 4). */
    float vertices[28][3] = {{0}};
    memcpy(vertices + 4, cube, sizeof cube);
    for (int f = 0; f < 6; ++f) {
        const GLushort b = (GLushort)(4 * f);
        const GLushort t[6] = {b, (GLushort)(b + 1), (GLushort)(b + 2), b, (GLushort)(b + 2), (GLushort)(b + 3)};
        memcpy(triangles + 6 * f, t, sizeof t);
        const GLushort s[4] = {b, (GLushort)(b + 1), (GLushort)(b + 3), (GLushort)(b + 2)};
        memcpy(strips + 5 * f, s, sizeof s);
        if (f < 5) strips[5 * f + 4] = 0xFFFF;
    }
    glBindBuffer(GL_ARRAY_BUFFER, vbo);
    glBufferData(GL_ARRAY_BUFFER, sizeof vertices, vertices, GL_STATIC_DRAW);
    const float offsets[2][3] = {{0, 0, 0}, {30, 0, 0}};
    glBindBuffer(GL_ARRAY_BUFFER, inst);
    glBufferData(GL_ARRAY_BUFFER, sizeof offsets, offsets, GL_DYNAMIC_DRAW);

    /* Vertex array objects: A reads the cube at offset 48 (no base vertex
     * needed), B the whole buffer (base vertex 4), C as B with per-instance
     * offsets; F the floor. */
    GLuint vao[4];
    glGenVertexArrays(4, vao);
    for (int i = 0; i < 3; ++i) {
        glBindVertexArray(vao[i]);
        glBindBuffer(GL_ARRAY_BUFFER, vbo);
        glEnableVertexAttribArray(0);
        glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 12, (const void*)(size_t)(i == 0 ? 48 : 0));
        glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, ibo);
    }
    glBufferData(GL_ELEMENT_ARRAY_BUFFER, sizeof triangles + sizeof strips, NULL, GL_STATIC_DRAW);
    glBufferSubData(GL_ELEMENT_ARRAY_BUFFER, 0, sizeof triangles, triangles);
    glBufferSubData(GL_ELEMENT_ARRAY_BUFFER, sizeof triangles, sizeof strips, strips);
    glBindVertexArray(vao[2]);
    glBindBuffer(GL_ARRAY_BUFFER, inst);
    glEnableVertexAttribArray(3);
    glVertexAttribPointer(3, 3, GL_FLOAT, GL_FALSE, 0, 0);
    glVertexAttribDivisor(3, 1);
    /* The floor: 40 x 40 at z = -50, short integers written through a mapping. */
    glBindVertexArray(vao[3]);
    glBindBuffer(GL_ARRAY_BUFFER, floor_vbo);
    glBufferData(GL_ARRAY_BUFFER, 4 * 3 * sizeof(GLshort), NULL, GL_STATIC_DRAW);
    GLshort* p = glMapBufferRange(GL_ARRAY_BUFFER, 0, 4 * 3 * sizeof(GLshort), GL_MAP_WRITE_BIT);
    const GLshort floor_quad[4][3] = {{0, 40, -50}, {40, 40, -50}, {40, 80, -50}, {0, 80, -50}};
    memcpy(p, floor_quad, sizeof floor_quad);
    glUnmapBuffer(GL_ARRAY_BUFFER);
    glEnableVertexAttribArray(0);
    glVertexAttribPointer(0, 3, GL_SHORT, GL_FALSE, 0, 0);

    /* A depth-only pass into a 64 x 64 framebuffer object (a shadow map). */
    GLuint depth_tex, fbo;
    glGenTextures(1, &depth_tex);
    glBindTexture(GL_TEXTURE_2D, depth_tex);
    glTexImage2D(GL_TEXTURE_2D, 0, GL_DEPTH_COMPONENT24, 64, 64, 0, GL_DEPTH_COMPONENT, GL_UNSIGNED_INT, NULL);
    glGenFramebuffers(1, &fbo);
    glBindFramebuffer(GL_FRAMEBUFFER, fbo);
    glFramebufferTexture2D(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_TEXTURE_2D, depth_tex, 0);
    glDrawBuffer(GL_NONE);

    glEnable(GL_DEPTH_TEST);
    glEnable(GL_CULL_FACE);
    glVertexAttrib3f(3, 0, 0, 0);   /* the offset of draws whose VAO leaves it disabled */
    for (int frame = 0; frame < 2; ++frame) {
        glBindFramebuffer(GL_FRAMEBUFFER, fbo);
        glViewport(0, 0, 64, 64);
        glClear(GL_DEPTH_BUFFER_BIT);
        glBindVertexArray(vao[0]);
        begin_object(1);
        model(8, 8, -20, 28, 28, -10);
        glDrawElements(GL_TRIANGLES, 36, GL_UNSIGNED_SHORT, 0);
        end_object();

        glBindFramebuffer(GL_FRAMEBUFFER, 0);
        glViewport(0, 0, w, h);
        glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
        begin_object(1);   /* box 1: [8,28] x [8,28] x [-20,-10] */
        if (frame == 0) {
            glDrawElements(GL_TRIANGLES, 36, GL_UNSIGNED_SHORT, 0);
        } else {
            glUseProgram(effects);
            float m[16];
            matrix_box(m, 8, 8, -20, 28, 28, -10);
            glUniformMatrix4fv(effects_model_at, 1, GL_FALSE, m);
            glDrawRangeElements(GL_TRIANGLES, 0, 23, 36, GL_UNSIGNED_SHORT, 0);
            glUseProgram(prog);
        }
        end_object();
        glBindVertexArray(vao[1]);
        begin_object(2);   /* box 2: [20,40] x [16,36] x [-15,-5] */
        model(20, 16, -15, 40, 36, -5);
        if (frame == 0) {
            glDrawElementsBaseVertex(GL_TRIANGLES, 36, GL_UNSIGNED_SHORT, 0, 4);
        } else {
            glEnable(GL_PRIMITIVE_RESTART);
            glPrimitiveRestartIndex(0xFFFF);
            glDrawElementsBaseVertex(GL_TRIANGLE_STRIP, 29, GL_UNSIGNED_SHORT, (const void*)sizeof triangles, 4);
            glDisable(GL_PRIMITIVE_RESTART);
        }
        end_object();
        glBindVertexArray(vao[2]);
        begin_object(3);   /* boxes 3 and 4: [60,70] x [8,18] x [-10,-5], and 30 to the right */
        model(60, 8, -10, 70, 18, -5);
        glDrawElementsInstancedBaseVertex(GL_TRIANGLES, 36, GL_UNSIGNED_SHORT, 0, 2, 4);
        end_object();
        if (frame == 1) {
            glBindVertexArray(vao[1]);
            inject_fault(prog);
        }
        glDebugMessageInsert(GL_DEBUG_SOURCE_APPLICATION, GL_DEBUG_TYPE_MARKER, 0, GL_DEBUG_SEVERITY_NOTIFICATION, -1,
                             "Floor pass");   /* a pass's name, as games mark theirs */
        glBindVertexArray(vao[3]);   /* the floor: other work */
        model(0, 0, 0, 1, 1, 1);
        glDrawArrays(GL_TRIANGLE_FAN, 0, 4);
        glXSwapBuffers(dpy, win);
        if (frame == 0) {
            /* Frame 1: the view moves everything 4 up; box 4 moves 10 more right. */
            const float up[2] = {0, 4};
            glBindBuffer(GL_UNIFORM_BUFFER, ubo);
            glBufferSubData(GL_UNIFORM_BUFFER, (16 + 12) * sizeof(float), sizeof up, up);
            const float right = 40;
            glBindBuffer(GL_ARRAY_BUFFER, inst);
            glBufferSubData(GL_ARRAY_BUFFER, 3 * sizeof(float), sizeof right, &right);
        }
    }
    glXMakeCurrent(dpy, None, NULL);
    glXDestroyContext(dpy, ctx);
    XCloseDisplay(dpy);
    return 0;
}

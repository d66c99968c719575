#include "bench/llvmpipe.h"

#include <chrono>
#include <cstdlib>
#include <ctime>

#define EGL_EGLEXT_PROTOTYPES
#include <EGL/egl.h>
#include <EGL/eglext.h>
#define GL_GLEXT_PROTOTYPES
#include <GL/gl.h>
#include <GL/glext.h>

namespace va::bench {

namespace {
double processCpu() {
    timespec ts;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
    return double(ts.tv_sec) + 1e-9 * double(ts.tv_nsec);
}
double wallNow() { return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count(); }

GLuint compile(GLenum type, const char *src, std::string *err) {
    const GLuint s = glCreateShader(type);
    glShaderSource(s, 1, &src, nullptr);
    glCompileShader(s);
    GLint ok = 0;
    glGetShaderiv(s, GL_COMPILE_STATUS, &ok);
    if (!ok) {
        char log[1024] = {};
        glGetShaderInfoLog(s, sizeof log, nullptr, log);
        *err = std::string("shader: ") + log;
    }
    return s;
}
}  // namespace

LlvmpipeRun drawWithLlvmpipe(const std::vector<float> &positions, const std::vector<uint32_t> &indices,
                             const float clipFromWorld[16], int width, int height, int reps) {
    LlvmpipeRun r;
    // llvmpipe reads these when the display is initialized: Mesa's software rasterizer, no
    // rasterizer threads (all work on this thread).
    setenv("LP_NUM_THREADS", "0", 1);
    setenv("GALLIUM_DRIVER", "llvmpipe", 1);
    setenv("LIBGL_ALWAYS_SOFTWARE", "1", 1);

    EGLDisplay dpy = eglGetPlatformDisplay(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr);
    EGLint major = 0, minor = 0;
    if (dpy == EGL_NO_DISPLAY || !eglInitialize(dpy, &major, &minor)) {
        r.error = "EGL surfaceless display unavailable (Debian: libegl-mesa0, libgl1-mesa-dri)";
        return r;
    }
    if (!eglBindAPI(EGL_OPENGL_API)) {
        r.error = "eglBindAPI(EGL_OPENGL_API) failed";
        return r;
    }
    const EGLint ctxAttribs[] = {EGL_CONTEXT_MAJOR_VERSION, 3, EGL_CONTEXT_MINOR_VERSION, 3,
                                 EGL_CONTEXT_OPENGL_PROFILE_MASK, EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT, EGL_NONE};
    // Surfaceless: no config and no surface (EGL_KHR_no_config_context, EGL_KHR_surfaceless_context).
    EGLContext ctx = eglCreateContext(dpy, EGL_NO_CONFIG_KHR, EGL_NO_CONTEXT, ctxAttribs);
    if (ctx == EGL_NO_CONTEXT || !eglMakeCurrent(dpy, EGL_NO_SURFACE, EGL_NO_SURFACE, ctx)) {
        r.error = "could not create an OpenGL 3.3 core context on the surfaceless display";
        eglTerminate(dpy);
        return r;
    }
    const char *renderer = reinterpret_cast<const char *>(glGetString(GL_RENDERER));
    r.renderer = renderer ? renderer : "";
    if (r.renderer.find("llvmpipe") == std::string::npos) {
        r.error = "the renderer is '" + r.renderer + "', not llvmpipe";
        eglMakeCurrent(dpy, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
        eglTerminate(dpy);
        return r;
    }

    // Depth-stencil only framebuffer: D24S8 renderbuffer, no color attachment, color writes off.
    GLuint fbo = 0, rb = 0;
    glGenFramebuffers(1, &fbo);
    glBindFramebuffer(GL_FRAMEBUFFER, fbo);
    glGenRenderbuffers(1, &rb);
    glBindRenderbuffer(GL_RENDERBUFFER, rb);
    glRenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH24_STENCIL8, width, height);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_STENCIL_ATTACHMENT, GL_RENDERBUFFER, rb);
    glDrawBuffer(GL_NONE);
    glReadBuffer(GL_NONE);
    if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE) {
        r.error = "the depth24_stencil8 framebuffer is incomplete";
        return r;
    }
    glColorMask(GL_FALSE, GL_FALSE, GL_FALSE, GL_FALSE);
    glViewport(0, 0, width, height);
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_LESS);
    glDisable(GL_CULL_FACE);
    glFrontFace(GL_CCW);
    glCullFace(GL_BACK);

    // The same world-space triangles and the same clip-from-world transform as the z-buffer.
    std::string err;
    const GLuint vs = compile(GL_VERTEX_SHADER,
                              "#version 330 core\nlayout(location = 0) in vec3 p;\nuniform mat4 clipFromWorld;\n"
                              "void main() { gl_Position = clipFromWorld * vec4(p, 1.0); }\n",
                              &err);
    const GLuint fs = compile(GL_FRAGMENT_SHADER, "#version 330 core\nvoid main() {}\n", &err);
    if (!err.empty()) {
        r.error = err;
        return r;
    }
    const GLuint prog = glCreateProgram();
    glAttachShader(prog, vs);
    glAttachShader(prog, fs);
    glLinkProgram(prog);
    glUseProgram(prog);
    glUniformMatrix4fv(glGetUniformLocation(prog, "clipFromWorld"), 1, GL_TRUE, clipFromWorld);
    GLuint vao = 0, buf[2] = {0, 0};
    glGenVertexArrays(1, &vao);
    glBindVertexArray(vao);
    glGenBuffers(2, buf);
    glBindBuffer(GL_ARRAY_BUFFER, buf[0]);
    glBufferData(GL_ARRAY_BUFFER, GLsizeiptr(positions.size() * sizeof(float)), positions.data(), GL_STATIC_DRAW);
    glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 3 * sizeof(float), nullptr);
    glEnableVertexAttribArray(0);
    glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, buf[1]);
    glBufferData(GL_ELEMENT_ARRAY_BUFFER, GLsizeiptr(indices.size() * sizeof(uint32_t)), indices.data(),
                 GL_STATIC_DRAW);
    const GLsizei count = GLsizei(indices.size());

    auto frame = [&] {
        glClear(GL_DEPTH_BUFFER_BIT | GL_STENCIL_BUFFER_BIT);
        glDrawElements(GL_TRIANGLES, count, GL_UNSIGNED_INT, nullptr);
        glFinish();
    };
    // The counts, outside the timed frames: fragments (depth test ALWAYS) and depth passes (LESS).
    GLuint q = 0;
    glGenQueries(1, &q);
    for (GLenum func : {GL_ALWAYS, GL_LESS}) {
        glDepthFunc(func);
        glClear(GL_DEPTH_BUFFER_BIT | GL_STENCIL_BUFFER_BIT);
        glBeginQuery(GL_SAMPLES_PASSED, q);
        glDrawElements(GL_TRIANGLES, count, GL_UNSIGNED_INT, nullptr);
        glEndQuery(GL_SAMPLES_PASSED);
        GLuint64 n = 0;
        glGetQueryObjectui64v(q, GL_QUERY_RESULT, &n);
        (func == GL_ALWAYS ? r.samplesCovered : r.samplesPassed) = n;
    }
    glDepthFunc(GL_LESS);
    frame();  // warm-up: shaders and state are compiled at the first draw
    for (int i = 0; i < reps; ++i) {
        const double c0 = processCpu(), w0 = wallNow();
        frame();
        r.cpuSeconds.push_back(processCpu() - c0);
        r.wallSeconds.push_back(wallNow() - w0);
    }
    glEnable(GL_CULL_FACE);
    frame();
    for (int i = 0; i < reps; ++i) {
        const double c0 = processCpu();
        frame();
        r.cullCpuSeconds.push_back(processCpu() - c0);
    }
    const GLenum glErr = glGetError();
    if (glErr != GL_NO_ERROR) {
        r.error = "GL error " + std::to_string(glErr);
        return r;
    }
    glDeleteQueries(1, &q);
    glDeleteBuffers(2, buf);
    glDeleteVertexArrays(1, &vao);
    glDeleteProgram(prog);
    glDeleteShader(vs);
    glDeleteShader(fs);
    glDeleteRenderbuffers(1, &rb);
    glDeleteFramebuffers(1, &fbo);
    eglMakeCurrent(dpy, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
    eglDestroyContext(dpy, ctx);
    eglTerminate(dpy);
    r.ok = true;
    return r;
}

}  // namespace va::bench

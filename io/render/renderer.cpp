#include "io/render/renderer.h"

#include <algorithm>
#include <span>
#include <chrono>
#include <cmath>
#include <cstring>
#include <limits>
#include <mutex>
#include <stdexcept>
#include <string>

#include <dlfcn.h>

#include <GL/gl.h>
#include <GL/osmesa.h>
#include <glm/geometric.hpp>
#include <glm/gtc/type_ptr.hpp>

namespace vdiso {

namespace {

// Client-side arrays are copied by Mesa at each draw call, for the vertex range the call's
// indices span; bounded draws keep those copies bounded (extractors emit vertices close to the
// triangles that use them).
constexpr size_t kTrianglesPerDraw = size_t(1) << 20;
constexpr size_t kPointsPerDraw = size_t(1) << 20;
constexpr float kSpecular = 0.2f;
constexpr float kShininess = 40.0f;

// OSMesa pulls in llvmpipe and LLVM: about 50 MB resident and tens of milliseconds of
// relocation at start-up. It is loaded on the first render instead of linked, so every command
// that does not draw stays small and starts fast. The entry points keep their GL names.
#define VDISO_GL_ENTRY_POINTS(X) \
    X(OSMesaCreateContextExt) \
    X(OSMesaMakeCurrent) \
    X(glClear) \
    X(glClearColor) \
    X(glClearDepth) \
    X(glDepthFunc) \
    X(glDepthRange) \
    X(glDisable) \
    X(glDisableClientState) \
    X(glDrawArrays) \
    X(glDrawElements) \
    X(glEnable) \
    X(glEnableClientState) \
    X(glFinish) \
    X(glGetError) \
    X(glLightModelfv) \
    X(glLightModeli) \
    X(glLightf) \
    X(glLightfv) \
    X(glLoadIdentity) \
    X(glLoadMatrixd) \
    X(glMaterialf) \
    X(glMaterialfv) \
    X(glMatrixMode) \
    X(glNormalPointer) \
    X(glPixelStorei) \
    X(glPointSize) \
    X(glReadPixels) \
    X(glShadeModel) \
    X(glVertexPointer) \
    X(glViewport) \

struct GlApi {
#define VDISO_GL_MEMBER(name) decltype(&::name) name = nullptr;
    VDISO_GL_ENTRY_POINTS(VDISO_GL_MEMBER)
#undef VDISO_GL_MEMBER
};

constexpr const char* kOsMesaLibrary = "libOSMesa.so.8";

const GlApi& gl() {
    static const GlApi api = [] {
        void* library = ::dlopen(kOsMesaLibrary, RTLD_NOW | RTLD_LOCAL);
        if (!library)
            throw std::runtime_error(std::string("cannot load ") + kOsMesaLibrary +
                                     " for rendering (Debian package libosmesa6): " + ::dlerror());
        GlApi loaded;
#define VDISO_GL_LOAD(name)                                                                  \
    loaded.name = reinterpret_cast<decltype(loaded.name)>(::dlsym(library, #name));          \
    if (!loaded.name)                                                                        \
        throw std::runtime_error(std::string(kOsMesaLibrary) + " has no " #name);
        VDISO_GL_ENTRY_POINTS(VDISO_GL_LOAD)
#undef VDISO_GL_LOAD
        return loaded;
    }();
    return api;
}

std::mutex gContextMutex;

// The one context, made on first use and kept for the life of the process: contexts are
// costly to make (llvmpipe compiles its shaders per context), and destroying one from a static
// destructor would race Mesa's own teardown at exit.
OSMesaContext sharedContext() {
    static OSMesaContext context = [] {
        OSMesaContext c = gl().OSMesaCreateContextExt(OSMESA_RGBA, 24, 0, 0, nullptr);
        if (!c)
            throw std::runtime_error(
                "OSMesa: cannot create an off-screen GL context (RGBA, 24-bit depth)");
        return c;
    }();
    return context;
}

// Unbinds the caller's colour buffer from the context, on every path out of renderSurface.
struct CurrentContext {
    CurrentContext(OSMesaContext context, void* buffer, int width, int height) {
        if (!gl().OSMesaMakeCurrent(context, buffer, GL_UNSIGNED_BYTE, width, height))
            throw std::runtime_error("OSMesa: cannot bind a " + std::to_string(width) + "x" +
                                     std::to_string(height) + " colour buffer");
    }
    ~CurrentContext() { gl().OSMesaMakeCurrent(nullptr, nullptr, 0, 0, 0); }
    CurrentContext(const CurrentContext&) = delete;
    CurrentContext& operator=(const CurrentContext&) = delete;
};

void boundsOf(std::span<const glm::vec3> positions, glm::dvec3& lo, glm::dvec3& hi) {
    for (const glm::vec3& p : positions) {
        lo = glm::min(lo, glm::dvec3(p));
        hi = glm::max(hi, glm::dvec3(p));
    }
}

void setUpState(const Camera& camera, const RenderStyle& style) {
    gl().glViewport(0, 0, camera.width, camera.height);
    gl().glClearColor(style.background.r, style.background.g, style.background.b, 1.0f);
    gl().glClearDepth(1.0);
    gl().glEnable(GL_DEPTH_TEST);
    gl().glDepthFunc(GL_LESS);
    gl().glDepthRange(0.0, 1.0);
    gl().glDisable(GL_CULL_FACE);
    gl().glDisable(GL_BLEND);
    gl().glDisable(GL_POINT_SMOOTH);
    gl().glShadeModel(GL_SMOOTH);
    gl().glEnable(GL_NORMALIZE);
    gl().glPointSize(style.pointSize);

    gl().glMatrixMode(GL_PROJECTION);
    gl().glLoadMatrixd(glm::value_ptr(camera.projectionMatrix()));
    gl().glMatrixMode(GL_MODELVIEW);
    // The light's position is taken in eye space when set: at the origin, it rides on the eye.
    gl().glLoadIdentity();
    const GLfloat atEye[] = {0.0f, 0.0f, 0.0f, 1.0f};
    const GLfloat white[] = {1.0f, 1.0f, 1.0f, 1.0f};
    const GLfloat direct[] = {1.0f - style.ambient, 1.0f - style.ambient, 1.0f - style.ambient,
                              1.0f};
    const GLfloat none[] = {0.0f, 0.0f, 0.0f, 1.0f};
    gl().glLightfv(GL_LIGHT0, GL_POSITION, atEye);
    gl().glLightfv(GL_LIGHT0, GL_AMBIENT, none);
    gl().glLightfv(GL_LIGHT0, GL_DIFFUSE, direct);
    gl().glLightfv(GL_LIGHT0, GL_SPECULAR, white);
    gl().glLightf(GL_LIGHT0, GL_CONSTANT_ATTENUATION, 1.0f);
    gl().glLightf(GL_LIGHT0, GL_LINEAR_ATTENUATION, 0.0f);
    gl().glLightf(GL_LIGHT0, GL_QUADRATIC_ATTENUATION, 0.0f);
    gl().glEnable(GL_LIGHT0);
    gl().glEnable(GL_LIGHTING);
    const GLfloat ambient[] = {style.ambient, style.ambient, style.ambient, 1.0f};
    gl().glLightModelfv(GL_LIGHT_MODEL_AMBIENT, ambient);
    gl().glLightModeli(GL_LIGHT_MODEL_TWO_SIDE, GL_TRUE);
    gl().glLightModeli(GL_LIGHT_MODEL_LOCAL_VIEWER, GL_TRUE);
    gl().glDisable(GL_COLOR_MATERIAL);

    const GLfloat color[] = {style.surfaceColor.r, style.surfaceColor.g, style.surfaceColor.b,
                             1.0f};
    const GLfloat specular[] = {kSpecular, kSpecular, kSpecular, 1.0f};
    gl().glMaterialfv(GL_FRONT_AND_BACK, GL_AMBIENT, color);
    gl().glMaterialfv(GL_FRONT_AND_BACK, GL_DIFFUSE, color);
    gl().glMaterialfv(GL_FRONT_AND_BACK, GL_SPECULAR, specular);
    gl().glMaterialfv(GL_FRONT_AND_BACK, GL_EMISSION, none);
    gl().glMaterialf(GL_FRONT_AND_BACK, GL_SHININESS, kShininess);

    gl().glLoadMatrixd(glm::value_ptr(camera.viewMatrix()));
}

void drawTriangles(const TriangleMesh& mesh) {
    if (mesh.indices.empty()) return;
    gl().glVertexPointer(3, GL_FLOAT, 0, mesh.positions.data());
    gl().glNormalPointer(GL_FLOAT, 0, mesh.normals.data());
    const size_t triangles = mesh.triangleCount();
    for (size_t first = 0; first < triangles; first += kTrianglesPerDraw) {
        const size_t count = std::min(kTrianglesPerDraw, triangles - first);
        gl().glDrawElements(GL_TRIANGLES, GLsizei(count * 3), GL_UNSIGNED_INT,
                       mesh.indices.data() + first * 3);
    }
}

// GL never treats a point as back-facing, so two-sided lighting is done here: each normal is
// turned towards the eye. Client arrays are read during the draw call, so one chunk-sized
// buffer of turned normals serves all draws.
void drawPoints(const PointSet& points, const glm::dvec3& eye) {
    if (points.positions.empty()) return;
    std::vector<glm::vec3> facing(std::min(kPointsPerDraw, points.size()));
    const glm::vec3 eyef(eye);
    gl().glVertexPointer(3, GL_FLOAT, 0, points.positions.data());
    gl().glNormalPointer(GL_FLOAT, 0, facing.data());
    for (size_t first = 0; first < points.size(); first += kPointsPerDraw) {
        const size_t count = std::min(kPointsPerDraw, points.size() - first);
        for (size_t i = 0; i < count; ++i) {
            const glm::vec3& n = points.normals[first + i];
            facing[i] = glm::dot(n, eyef - points.positions[first + i]) < 0.0f ? -n : n;
        }
        gl().glDrawArrays(GL_POINTS, GLint(first), GLsizei(count));
    }
}

}  // namespace

RenderResult renderSurface(const TriangleMesh& mesh, const PointSet& points, const Camera& camera,
                           const RenderStyle& style) {
    if (camera.width < 1 || camera.height < 1 || camera.width > kMaxRenderSide ||
        camera.height > kMaxRenderSide)
        throw std::invalid_argument("renderSurface: image size " + std::to_string(camera.width) +
                                    "x" + std::to_string(camera.height) + " is not within 1.." +
                                    std::to_string(kMaxRenderSide));
    if (mesh.normals.size() != mesh.positions.size() || mesh.indices.size() % 3 != 0 ||
        points.normals.size() != points.positions.size())
        throw std::invalid_argument("renderSurface: positions, normals and indices disagree");
    if (points.size() > size_t(std::numeric_limits<GLint>::max()))
        throw std::invalid_argument("renderSurface: too many points for one GL array");

    RenderResult result;
    result.camera = camera;
    if (!camera.hasClipPlanes()) {
        glm::dvec3 lo(std::numeric_limits<double>::infinity());
        glm::dvec3 hi(-std::numeric_limits<double>::infinity());
        boundsOf(mesh.positions, lo, hi);
        boundsOf(points.positions, lo, hi);
        if (lo.x <= hi.x) fitClipPlanes(result.camera, lo, hi);
    }
    const Camera& cam = result.camera;
    const int w = cam.width, h = cam.height;
    const size_t pixels = size_t(w) * size_t(h);

    std::lock_guard<std::mutex> lock(gContextMutex);
    std::vector<uint8_t> colorBuffer(pixels * 4);
    CurrentContext current(sharedContext(), colorBuffer.data(), w, h);
    while (gl().glGetError() != GL_NO_ERROR) {
    }

    setUpState(cam, style);
    gl().glEnableClientState(GL_VERTEX_ARRAY);
    gl().glEnableClientState(GL_NORMAL_ARRAY);
    gl().glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    gl().glFinish();

    const auto start = std::chrono::steady_clock::now();
    drawTriangles(mesh);
    drawPoints(points, cam.eye);
    gl().glFinish();
    result.drawSeconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    gl().glDisableClientState(GL_VERTEX_ARRAY);
    gl().glDisableClientState(GL_NORMAL_ARRAY);

    // GL's rows run bottom-up; ours top-down.
    gl().glPixelStorei(GL_PACK_ALIGNMENT, 1);
    std::vector<uint8_t> rgba(pixels * 4);
    std::vector<float> depth(pixels);
    gl().glReadPixels(0, 0, w, h, GL_RGBA, GL_UNSIGNED_BYTE, rgba.data());
    gl().glReadPixels(0, 0, w, h, GL_DEPTH_COMPONENT, GL_FLOAT, depth.data());
    if (GLenum error = gl().glGetError(); error != GL_NO_ERROR) {
        if (error == GL_OUT_OF_MEMORY)
            throw std::runtime_error("OpenGL: out of memory while rendering");
        throw std::runtime_error("OpenGL error " + std::to_string(error) + " while rendering");
    }

    result.image = RgbaImage(w, h);
    result.depth.resize(pixels);
    const size_t rowBytes = size_t(w) * 4;
    for (int y = 0; y < h; ++y) {
        const size_t from = size_t(h - 1 - y), to = size_t(y);
        std::memcpy(result.image.rgba.data() + to * rowBytes, rgba.data() + from * rowBytes,
                    rowBytes);
        std::memcpy(result.depth.data() + to * size_t(w), depth.data() + from * size_t(w),
                    size_t(w) * sizeof(float));
    }
    return result;
}

}  // namespace vdiso

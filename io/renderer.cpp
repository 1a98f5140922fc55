#include "io/renderer.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <limits>
#include <mutex>
#include <stdexcept>
#include <string>

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

std::mutex gContextMutex;

// The one context, made on first use and kept for the life of the process: contexts are
// costly to make (llvmpipe compiles its shaders per context), and destroying one from a static
// destructor would race Mesa's own teardown at exit.
OSMesaContext sharedContext() {
    static OSMesaContext context = [] {
        OSMesaContext c = OSMesaCreateContextExt(OSMESA_RGBA, 24, 0, 0, nullptr);
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
        if (!OSMesaMakeCurrent(context, buffer, GL_UNSIGNED_BYTE, width, height))
            throw std::runtime_error("OSMesa: cannot bind a " + std::to_string(width) + "x" +
                                     std::to_string(height) + " colour buffer");
    }
    ~CurrentContext() { OSMesaMakeCurrent(nullptr, nullptr, 0, 0, 0); }
    CurrentContext(const CurrentContext&) = delete;
    CurrentContext& operator=(const CurrentContext&) = delete;
};

void boundsOf(const std::vector<glm::vec3>& positions, glm::dvec3& lo, glm::dvec3& hi) {
    for (const glm::vec3& p : positions) {
        lo = glm::min(lo, glm::dvec3(p));
        hi = glm::max(hi, glm::dvec3(p));
    }
}

void setUpState(const Camera& camera, const RenderStyle& style) {
    glViewport(0, 0, camera.width, camera.height);
    glClearColor(style.background.r, style.background.g, style.background.b, 1.0f);
    glClearDepth(1.0);
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_LESS);
    glDepthRange(0.0, 1.0);
    glDisable(GL_CULL_FACE);
    glDisable(GL_BLEND);
    glDisable(GL_POINT_SMOOTH);
    glShadeModel(GL_SMOOTH);
    glEnable(GL_NORMALIZE);
    glPointSize(style.pointSize);

    glMatrixMode(GL_PROJECTION);
    glLoadMatrixd(glm::value_ptr(camera.projectionMatrix()));
    glMatrixMode(GL_MODELVIEW);
    // The light's position is taken in eye space when set: at the origin, it rides on the eye.
    glLoadIdentity();
    const GLfloat atEye[] = {0.0f, 0.0f, 0.0f, 1.0f};
    const GLfloat white[] = {1.0f, 1.0f, 1.0f, 1.0f};
    const GLfloat direct[] = {1.0f - style.ambient, 1.0f - style.ambient, 1.0f - style.ambient,
                              1.0f};
    const GLfloat none[] = {0.0f, 0.0f, 0.0f, 1.0f};
    glLightfv(GL_LIGHT0, GL_POSITION, atEye);
    glLightfv(GL_LIGHT0, GL_AMBIENT, none);
    glLightfv(GL_LIGHT0, GL_DIFFUSE, direct);
    glLightfv(GL_LIGHT0, GL_SPECULAR, white);
    glLightf(GL_LIGHT0, GL_CONSTANT_ATTENUATION, 1.0f);
    glLightf(GL_LIGHT0, GL_LINEAR_ATTENUATION, 0.0f);
    glLightf(GL_LIGHT0, GL_QUADRATIC_ATTENUATION, 0.0f);
    glEnable(GL_LIGHT0);
    glEnable(GL_LIGHTING);
    const GLfloat ambient[] = {style.ambient, style.ambient, style.ambient, 1.0f};
    glLightModelfv(GL_LIGHT_MODEL_AMBIENT, ambient);
    glLightModeli(GL_LIGHT_MODEL_TWO_SIDE, GL_TRUE);
    glLightModeli(GL_LIGHT_MODEL_LOCAL_VIEWER, GL_TRUE);
    glDisable(GL_COLOR_MATERIAL);

    const GLfloat color[] = {style.surfaceColor.r, style.surfaceColor.g, style.surfaceColor.b,
                             1.0f};
    const GLfloat specular[] = {kSpecular, kSpecular, kSpecular, 1.0f};
    glMaterialfv(GL_FRONT_AND_BACK, GL_AMBIENT, color);
    glMaterialfv(GL_FRONT_AND_BACK, GL_DIFFUSE, color);
    glMaterialfv(GL_FRONT_AND_BACK, GL_SPECULAR, specular);
    glMaterialfv(GL_FRONT_AND_BACK, GL_EMISSION, none);
    glMaterialf(GL_FRONT_AND_BACK, GL_SHININESS, kShininess);

    glLoadMatrixd(glm::value_ptr(camera.viewMatrix()));
}

void drawTriangles(const TriangleMesh& mesh) {
    if (mesh.indices.empty()) return;
    glVertexPointer(3, GL_FLOAT, 0, mesh.positions.data());
    glNormalPointer(GL_FLOAT, 0, mesh.normals.data());
    const size_t triangles = mesh.triangleCount();
    for (size_t first = 0; first < triangles; first += kTrianglesPerDraw) {
        const size_t count = std::min(kTrianglesPerDraw, triangles - first);
        glDrawElements(GL_TRIANGLES, GLsizei(count * 3), GL_UNSIGNED_INT,
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
    glVertexPointer(3, GL_FLOAT, 0, points.positions.data());
    glNormalPointer(GL_FLOAT, 0, facing.data());
    for (size_t first = 0; first < points.size(); first += kPointsPerDraw) {
        const size_t count = std::min(kPointsPerDraw, points.size() - first);
        for (size_t i = 0; i < count; ++i) {
            const glm::vec3& n = points.normals[first + i];
            facing[i] = glm::dot(n, eyef - points.positions[first + i]) < 0.0f ? -n : n;
        }
        glDrawArrays(GL_POINTS, GLint(first), GLsizei(count));
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
    while (glGetError() != GL_NO_ERROR) {
    }

    setUpState(cam, style);
    glEnableClientState(GL_VERTEX_ARRAY);
    glEnableClientState(GL_NORMAL_ARRAY);
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    glFinish();

    const auto start = std::chrono::steady_clock::now();
    drawTriangles(mesh);
    drawPoints(points, cam.eye);
    glFinish();
    result.drawSeconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    glDisableClientState(GL_VERTEX_ARRAY);
    glDisableClientState(GL_NORMAL_ARRAY);

    // GL's rows run bottom-up; ours top-down.
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    std::vector<uint8_t> rgba(pixels * 4);
    std::vector<float> depth(pixels);
    glReadPixels(0, 0, w, h, GL_RGBA, GL_UNSIGNED_BYTE, rgba.data());
    glReadPixels(0, 0, w, h, GL_DEPTH_COMPONENT, GL_FLOAT, depth.data());
    if (GLenum error = glGetError(); error != GL_NO_ERROR) {
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

// The OSMesa renderer (coverage, depth, lighting, points) and PNG files.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <numbers>
#include <set>
#include <stdexcept>
#include <utility>

#include <glm/geometric.hpp>
#include <png.h>

#include "core/camera.h"
#include "core/view_presets.h"
#include "io/error.h"
#include "io/render/png_image.h"
#include "io/render/renderer.h"
#include "tests/test_util.h"

namespace vdiso {
namespace {

using test::ScratchDir;

// The unit cube [0,1]^3: 6 faces of 2 triangles, flat outward normals, counter-clockwise seen
// from outside.
TriangleMesh unitCube() {
    TriangleMesh mesh;
    for (int axis = 0; axis < 3; ++axis) {
        for (int side = 0; side < 2; ++side) {
            glm::vec3 n(0.0f);
            n[axis] = side ? 1.0f : -1.0f;
            const int u = (axis + 1) % 3, v = (axis + 2) % 3;
            const uint32_t base = uint32_t(mesh.positions.size());
            for (int k = 0; k < 4; ++k) {
                glm::vec3 p(0.0f);
                p[axis] = float(side);
                p[u] = float(k == 1 || k == 2);
                p[v] = float(k >= 2);
                mesh.positions.push_back(p);
                mesh.normals.push_back(n);
            }
            // (u, v, axis) is right-handed: quad 0,1,2,3 runs counter-clockwise seen from +axis.
            const uint32_t ccw[] = {0, 1, 2, 0, 2, 3}, cw[] = {0, 2, 1, 0, 3, 2};
            for (uint32_t i : side ? ccw : cw) mesh.indices.push_back(base + i);
        }
    }
    return mesh;
}

bool isBackground(const RgbaImage& image, int x, int y, const RenderStyle& style) {
    const uint8_t* p = image.pixel(x, y);
    for (int c = 0; c < 3; ++c)
        if (std::abs(int(p[c]) - int(std::lround(style.background[c] * 255.0f))) > 1) return false;
    return p[3] == 255;
}

float depthAt(const RenderResult& r, int x, int y) {
    return r.depth[size_t(y) * size_t(r.image.width) + size_t(x)];
}

TEST(Render, CubeCoversTheCentreAndNotTheCorners) {
    const RenderStyle style;
    const Camera camera = presetCamera(ViewPreset::Normal, glm::dvec3(0.0), glm::dvec3(1.0),
                                       160, 120);
    const RenderResult r = renderSurface(unitCube(), {}, camera, style);
    ASSERT_EQ(r.image.width, 160);
    ASSERT_EQ(r.image.height, 120);
    ASSERT_EQ(r.depth.size(), 160u * 120u);
    EXPECT_GE(r.drawSeconds, 0.0);

    EXPECT_LT(depthAt(r, 80, 60), 1.0f);
    EXPECT_FALSE(isBackground(r.image, 80, 60, style));
    for (auto [x, y] : {std::pair{0, 0}, {159, 0}, {0, 119}, {159, 119}}) {
        EXPECT_TRUE(isBackground(r.image, x, y, style)) << x << "," << y;
        EXPECT_EQ(depthAt(r, x, y), 1.0f);
    }

    // Colour and depth agree everywhere.
    int covered = 0;
    for (int y = 0; y < 120; ++y) {
        for (int x = 0; x < 160; ++x) {
            const bool drawn = depthAt(r, x, y) < 1.0f;
            EXPECT_EQ(drawn, !isBackground(r.image, x, y, style)) << x << "," << y;
            covered += drawn;
        }
    }
    EXPECT_GT(covered, 160 * 120 / 10);
}

// Seen straight on along -y, the cube's image is a square mirror-symmetric both ways (the
// preset's oblique view is not symmetric: its perspective is strong).
TEST(Render, CubeSeenHeadOnIsSymmetric) {
    Camera camera;
    camera.target = {0.5, 0.5, 0.5};
    camera.eye = {0.5, 4.0, 0.5};
    camera.up = {0.0, 0.0, 1.0};
    camera.width = 101;
    camera.height = 80;
    const RenderResult r = renderSurface(unitCube(), {}, camera);
    auto drawn = [&](int x, int y) { return depthAt(r, x, y) < 1.0f; };
    int covered = 0, asymmetric = 0, rows = 0, columns = 0;
    for (int y = 0; y < 80; ++y) {
        for (int x = 0; x < 101; ++x) {
            covered += drawn(x, y);
            asymmetric += drawn(x, y) != drawn(100 - x, y);
            asymmetric += drawn(x, y) != drawn(x, 79 - y);
        }
    }
    for (int x = 0; x < 101; ++x) columns += drawn(x, 40);
    for (int y = 0; y < 80; ++y) rows += drawn(50, y);
    // The front face (y = 1) at distance 3 spans 1 / (2 * 3 * tan 15deg) of the height.
    const double side = 80.0 / (2.0 * 3.0 * std::tan(std::numbers::pi / 12.0));
    EXPECT_NEAR(rows, side, 1.0);
    EXPECT_NEAR(columns, side, 1.0);
    EXPECT_NEAR(covered, side * side, 2.0 * side);
    EXPECT_LE(asymmetric, 4) << covered;
}

TEST(Render, DepthIsTheCamerasWindowDepth) {
    const Camera camera = presetCamera(ViewPreset::Normal, glm::dvec3(0.0), glm::dvec3(1.0),
                                       128, 128);
    const RenderResult r = renderSurface(unitCube(), {}, camera);
    int checked = 0;
    for (int y = 0; y < 128; y += 7) {
        for (int x = 0; x < 128; x += 7) {
            const float depth = depthAt(r, x, y);
            if (depth >= 1.0f) continue;
            // The point seen in the pixel's centre is on the cube's surface.
            const glm::dvec3 p = camera.unproject({x + 0.5, y + 0.5, depth});
            const double inside = std::max({std::abs(p.x - 0.5), std::abs(p.y - 0.5),
                                            std::abs(p.z - 0.5)});
            EXPECT_NEAR(inside, 0.5, 2e-3) << x << "," << y;
            ++checked;
        }
    }
    EXPECT_GT(checked, 20);
}

TEST(Render, CameraWithoutClipPlanesGetsThemFromTheGeometry) {
    Camera camera = presetCamera(ViewPreset::Normal, glm::dvec3(0.0), glm::dvec3(1.0), 64, 64);
    camera.zNear = camera.zFar = 0.0;
    const RenderResult r = renderSurface(unitCube(), {}, camera);
    EXPECT_TRUE(r.camera.hasClipPlanes());
    EXPECT_LT(depthAt(r, 32, 32), 1.0f);
}

// A square facing the eye, lit from the front; the same square with its normal and winding
// turned away from the eye must shade the same (two-sided lighting).
TEST(Render, BackFacesShadeLikeFrontFaces) {
    Camera camera;
    camera.eye = {0.0, 5.0, 0.0};
    camera.target = {0.0, 0.0, 0.0};
    camera.up = {0.0, 0.0, 1.0};
    camera.width = camera.height = 32;
    camera.zNear = 1.0;
    camera.zFar = 10.0;
    TriangleMesh front;
    front.positions = {{-1, 0, -1}, {1, 0, -1}, {1, 0, 1}, {-1, 0, 1}};
    front.normals.assign(4, glm::vec3(0, 1, 0));
    front.indices = {0, 2, 1, 0, 3, 2};  // counter-clockwise seen from +y
    TriangleMesh back = front;
    back.normals.assign(4, glm::vec3(0, -1, 0));
    back.indices = {0, 1, 2, 0, 2, 3};
    const RenderStyle style;
    const RenderResult a = renderSurface(front, {}, camera, style);
    const RenderResult b = renderSurface(back, {}, camera, style);
    const uint8_t* pa = a.image.pixel(16, 16);
    const uint8_t* pb = b.image.pixel(16, 16);
    for (int c = 0; c < 3; ++c) {
        EXPECT_NEAR(pa[c], pb[c], 1) << c;
        // Head-on: well above ambient.
        EXPECT_GT(pa[c], 0.8 * 255 * style.surfaceColor[c]) << c;
    }
}

// Points far apart, each at a pixel's centre: exactly those pixels are drawn, lit alike
// whichever way their normals point.
TEST(RenderPoints, ExactlyThePixelsThePointsProjectTo) {
    Camera camera = presetCamera(ViewPreset::Normal, glm::dvec3(0.0), glm::dvec3(1.0), 64, 48);
    const std::set<std::pair<int, int>> pixels = {{5, 7}, {30, 20}, {60, 40}, {10, 44}, {50, 3},
                                                  {0, 0}, {63, 47}};
    const double depth = camera.project(camera.target).z;
    PointSet points;
    int i = 0;
    for (auto [x, y] : pixels) {
        const glm::dvec3 p = camera.unproject({x + 0.5, y + 0.5, depth});
        points.positions.push_back(glm::vec3(p));
        const glm::vec3 toEye = glm::normalize(glm::vec3(camera.eye - p));
        points.normals.push_back(i++ % 2 ? toEye : -toEye);
    }
    const RenderStyle style;
    const RenderResult r = renderSurface({}, points, camera, style);
    const uint8_t* first = r.image.pixel(5, 7);
    for (int y = 0; y < 48; ++y) {
        for (int x = 0; x < 64; ++x) {
            const bool expected = pixels.count({x, y}) > 0;
            EXPECT_EQ(depthAt(r, x, y) < 1.0f, expected) << x << "," << y;
            EXPECT_EQ(!isBackground(r.image, x, y, style), expected) << x << "," << y;
            if (expected) {
                EXPECT_NEAR(depthAt(r, x, y), depth, 1e-5);
                for (int c = 0; c < 3; ++c) EXPECT_NEAR(r.image.pixel(x, y)[c], first[c], 1);
            }
        }
    }
    // Facing the headlight: brighter than ambient alone.
    EXPECT_GT(first[0], 0.8 * 255 * style.surfaceColor[0]);

    RenderStyle wide = style;
    wide.pointSize = 3.0f;
    const RenderResult r3 = renderSurface({}, points, camera, wide);
    int covered = 0;
    for (float d : r3.depth) covered += d < 1.0f;
    // 3x3 squares, less what falls off the two corner points' images.
    EXPECT_EQ(covered, 5 * 9 + 2 * 4);
}

TEST(Render, NothingToDrawIsAllBackgroundAndRejectsBadSizes) {
    Camera camera = presetCamera(ViewPreset::Normal, glm::dvec3(0.0), glm::dvec3(1.0), 16, 8);
    const RenderStyle style;
    const RenderResult r = renderSurface({}, {}, camera, style);
    for (float d : r.depth) EXPECT_EQ(d, 1.0f);
    for (int y = 0; y < 8; ++y)
        for (int x = 0; x < 16; ++x) EXPECT_TRUE(isBackground(r.image, x, y, style));
    camera.width = kMaxRenderSide + 1;
    EXPECT_THROW(renderSurface({}, {}, camera), std::invalid_argument);
    camera.width = 0;
    EXPECT_THROW(renderSurface({}, {}, camera), std::invalid_argument);
}

RgbaImage testImage(int w, int h) {
    RgbaImage image(w, h);
    for (size_t i = 0; i < image.rgba.size(); ++i) image.rgba[i] = uint8_t(i * 37 + i / 7);
    return image;
}

std::string errorOf(const std::string& path) {
    try {
        readPng(path);
    } catch (const IoError& e) {
        return e.what();
    }
    return "";
}

TEST(Png, RoundTripsEveryByte) {
    ScratchDir dir;
    for (auto [w, h] : {std::pair{1, 1}, {7, 3}, {64, 33}}) {
        const RgbaImage image = testImage(w, h);
        const std::string path = dir.file("img" + std::to_string(w) + ".png");
        writePng(path, image, false);
        const RgbaImage back = readPng(path);
        EXPECT_EQ(back.width, w);
        EXPECT_EQ(back.height, h);
        EXPECT_EQ(back.rgba, image.rgba);
    }
    // Nothing left behind but the outputs.
    EXPECT_EQ(std::distance(std::filesystem::directory_iterator(dir.path()), {}), 3);
}

TEST(Png, RendersWriteAndReadBack) {
    ScratchDir dir;
    const Camera camera = presetCamera(ViewPreset::Normal, glm::dvec3(0.0), glm::dvec3(1.0),
                                       48, 40);
    const RenderResult r = renderSurface(unitCube(), {}, camera);
    writePng(dir.file("cube.png"), r.image, false);
    EXPECT_EQ(readPng(dir.file("cube.png")).rgba, r.image.rgba);
}

TEST(Png, OtherColorTypesReadAsRgba) {
    ScratchDir dir;
    // An 8-bit grey PNG written with libpng directly.
    const int w = 5, h = 2;
    std::vector<uint8_t> grey(w * h);
    for (int i = 0; i < w * h; ++i) grey[i] = uint8_t(i * 25);
    png_image image{};
    image.version = PNG_IMAGE_VERSION;
    image.width = w;
    image.height = h;
    image.format = PNG_FORMAT_GRAY;
    const std::string path = dir.file("grey.png");
    ASSERT_TRUE(png_image_write_to_file(&image, path.c_str(), 0, grey.data(), w, nullptr));
    png_image_free(&image);
    const RgbaImage back = readPng(path);
    ASSERT_EQ(back.width, w);
    ASSERT_EQ(back.height, h);
    for (int i = 0; i < w * h; ++i) {
        const uint8_t* p = back.pixel(i % w, i / w);
        EXPECT_EQ(p[0], grey[i]);
        EXPECT_EQ(p[1], grey[i]);
        EXPECT_EQ(p[2], grey[i]);
        EXPECT_EQ(p[3], 255);
    }
}

TEST(Png, NotPngAndTruncatedFilesNameTheFile) {
    ScratchDir dir;
    const std::string text = dir.file("notes.png");
    test::writeFile(text, "this is not an image, just text long enough");
    std::string message = errorOf(text);
    EXPECT_EQ(message.rfind(text + ": ", 0), 0u) << message;
    EXPECT_NE(message.find("not a PNG file"), std::string::npos) << message;
    test::writeFile(text, "");
    EXPECT_NE(errorOf(text).find("not a PNG file"), std::string::npos);

    const std::string good = dir.file("good.png");
    writePng(good, testImage(40, 30), false);
    const std::vector<unsigned char> bytes = test::readFile(good);
    for (size_t keep : {size_t(8), size_t(40), bytes.size() / 2, bytes.size() - 13}) {
        const std::string cut = dir.file("cut" + std::to_string(keep) + ".png");
        test::writeFile(cut, bytes.data(), keep);
        message = errorOf(cut);
        EXPECT_EQ(message.rfind(cut + ": ", 0), 0u) << keep << ": " << message;
    }
    message = errorOf(dir.file("absent.png"));
    EXPECT_NE(message.find("absent.png: cannot open"), std::string::npos) << message;
}

TEST(Png, ExistingFileIsKeptUnlessOverwriteIsAsked) {
    ScratchDir dir;
    const std::string path = dir.file("out.png");
    test::writeFile(path, "precious");
    try {
        writePng(path, testImage(4, 4), false);
        FAIL() << "no exception";
    } catch (const IoError& e) {
        EXPECT_EQ(std::string(e.what()).rfind(path + ": ", 0), 0u) << e.what();
    }
    const std::vector<unsigned char> kept = test::readFile(path);
    EXPECT_EQ(std::string(kept.begin(), kept.end()), "precious");
    EXPECT_EQ(std::distance(std::filesystem::directory_iterator(dir.path()), {}), 1);

    writePng(path, testImage(4, 4), true);
    EXPECT_EQ(readPng(path).rgba, testImage(4, 4).rgba);
    EXPECT_THROW(writePng(dir.file("bad.png"), RgbaImage(), false), std::invalid_argument);
}

}  // namespace
}  // namespace vdiso

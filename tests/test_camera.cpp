// Cameras: the pixel convention, clip planes, the SAGE view presets, and camera JSON files.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <glm/geometric.hpp>
#include <glm/trigonometric.hpp>

#include "core/camera.h"
#include "core/view_presets.h"
#include "io/camera_json.h"
#include "io/error.h"
#include "tests/test_util.h"

namespace vdiso {
namespace {

using test::ScratchDir;

Camera obliqueCamera() {
    Camera c;
    c.eye = {3.0, -7.0, 2.5};
    c.target = {0.5, 0.25, -0.5};
    c.up = {0.0, 0.0, 1.0};
    c.fovYDegrees = 40.0;
    c.width = 320;
    c.height = 200;
    c.zNear = 1.0;
    c.zFar = 50.0;
    return c;
}

glm::dvec3 corner(const glm::dvec3& lo, const glm::dvec3& hi, int i) {
    return {i & 1 ? hi.x : lo.x, i & 2 ? hi.y : lo.y, i & 4 ? hi.z : lo.z};
}

TEST(CameraProjection, TargetLandsAtTheImageCentre) {
    const Camera c = obliqueCamera();
    const glm::dvec3 p = c.project(c.target);
    EXPECT_NEAR(p.x, 160.0, 1e-9);
    EXPECT_NEAR(p.y, 100.0, 1e-9);
    EXPECT_GT(p.z, 0.0);
    EXPECT_LT(p.z, 1.0);
}

TEST(CameraProjection, UpIsSmallerYAndRightIsLargerX) {
    const Camera c = obliqueCamera();
    const glm::dvec3 centre = c.project(c.target);
    const glm::dvec3 above = c.project(c.target + glm::dvec3(0.0, 0.0, 0.5));
    EXPECT_LT(above.y, centre.y - 1.0);
    EXPECT_NEAR(above.x, centre.x, 1e-9);  // world up stays vertical in the image
    const glm::dvec3 right = glm::normalize(glm::cross(c.forward(), c.up));
    const glm::dvec3 toRight = c.project(c.target + right * 0.5);
    EXPECT_GT(toRight.x, centre.x + 1.0);
    EXPECT_NEAR(toRight.y, centre.y, 1e-9);
}

TEST(CameraProjection, DepthIsWindowDepthBetweenTheClipPlanes) {
    const Camera c = obliqueCamera();
    const glm::dvec3 f = c.forward();
    EXPECT_NEAR(c.project(c.eye + f * c.zNear).z, 0.0, 1e-9);
    EXPECT_NEAR(c.project(c.eye + f * c.zFar).z, 1.0, 1e-9);
    const double nearer = c.project(c.eye + f * 5.0).z, farther = c.project(c.eye + f * 6.0).z;
    EXPECT_LT(nearer, farther);
}

TEST(CameraProjection, UnprojectInvertsProject) {
    const Camera c = obliqueCamera();
    for (const glm::dvec3 world : {glm::dvec3(0.0), glm::dvec3(1.0, 2.0, -1.0),
                                   glm::dvec3(-2.0, 4.0, 3.0)}) {
        const glm::dvec3 back = c.unproject(c.project(world));
        EXPECT_NEAR(glm::length(back - world), 0.0, 1e-6);
    }
    // The top-left pixel's centre is (0.5, 0.5).
    const glm::dvec3 topLeft = c.unproject({0.5, 0.5, 0.5});
    const glm::dvec3 p = c.project(topLeft);
    EXPECT_NEAR(p.x, 0.5, 1e-6);
    EXPECT_NEAR(p.y, 0.5, 1e-6);
}

TEST(CameraProjection, BehindTheEyeIsNaN) {
    const Camera c = obliqueCamera();
    const glm::dvec3 p = c.project(c.eye - c.forward());
    EXPECT_TRUE(std::isnan(p.x) && std::isnan(p.y) && std::isnan(p.z));
}

TEST(CameraProjection, FittedClipPlanesHoldTheBox) {
    Camera c = obliqueCamera();
    const glm::dvec3 lo(-1.0, -2.0, -3.0), hi(2.0, 1.0, 0.5);
    fitClipPlanes(c, lo, hi);
    ASSERT_TRUE(c.hasClipPlanes());
    for (int i = 0; i < 8; ++i) {
        const double depth = c.project(corner(lo, hi, i)).z;
        EXPECT_GT(depth, 0.0);
        EXPECT_LT(depth, 1.0);
    }
    // Eye inside the box: the near plane is clamped, not zero or negative.
    c.eye = {0.0, 0.0, 0.0};
    fitClipPlanes(c, lo, hi);
    EXPECT_TRUE(c.hasClipPlanes());
    EXPECT_LE(c.zFar / c.zNear, 1000.0 + 1e-9);
}

struct PresetCase {
    glm::dvec3 lo, hi;
    int width, height;
};

const PresetCase kPresetCases[] = {
    {{0.0, 0.0, 0.0}, {1.0, 1.0, 1.0}, 800, 600},
    {{-10.0, -20.0, -5.0}, {30.0, 20.0, 45.0}, 800, 600},
    {{0.0, 0.0, 0.0}, {255.0, 255.0, 127.0}, 600, 800},   // portrait
    {{-90.0, -126.0, -72.0}, {91.0, 91.0, 109.0}, 1024, 256},  // MNI-like, wide
};

void expectAllCornersInView(const Camera& c, const PresetCase& k) {
    for (int i = 0; i < 8; ++i) {
        const glm::dvec3 p = c.project(corner(k.lo, k.hi, i));
        EXPECT_GT(p.x, 0.0);
        EXPECT_LT(p.x, c.width);
        EXPECT_GT(p.y, 0.0);
        EXPECT_LT(p.y, c.height);
        EXPECT_GT(p.z, 0.0);
        EXPECT_LT(p.z, 1.0);
    }
}

// The height of the box's image as a fraction of the image height.
double imageHeightFraction(const Camera& c, const PresetCase& k) {
    double top = 1e300, bottom = -1e300;
    for (int i = 0; i < 8; ++i) {
        const double y = c.project(corner(k.lo, k.hi, i)).y;
        top = std::min(top, y);
        bottom = std::max(bottom, y);
    }
    return (bottom - top) / c.height;
}

TEST(CameraPreset, NormalShowsTheWholeVolumeLarge) {
    for (const PresetCase& k : kPresetCases) {
        const Camera c = presetCamera(ViewPreset::Normal, k.lo, k.hi, k.width, k.height);
        EXPECT_EQ(c.width, k.width);
        EXPECT_EQ(c.height, k.height);
        EXPECT_DOUBLE_EQ(c.fovYDegrees, 30.0);
        EXPECT_GT(c.eye.y, k.hi.y);  // from the front
        EXPECT_GT(c.eye.z, c.target.z);  // from above
        expectAllCornersInView(c, k);
        double left = 1e300, right = -1e300;
        for (int i = 0; i < 8; ++i) {
            left = std::min(left, c.project(corner(k.lo, k.hi, i)).x);
            right = std::max(right, c.project(corner(k.lo, k.hi, i)).x);
        }
        // Large: the box spans at least 40% of one image side.
        EXPECT_GT(std::max(imageHeightFraction(c, k), (right - left) / c.width), 0.4);
    }
}

TEST(CameraPreset, DistantShowsTheWholeVolumeSmall) {
    for (const PresetCase& k : kPresetCases) {
        const Camera c = presetCamera(ViewPreset::Distant, k.lo, k.hi, k.width, k.height);
        expectAllCornersInView(c, k);
        // The bounding sphere's image is 1/10 of the height; the box's is a little less.
        const double fraction = imageHeightFraction(c, k);
        EXPECT_GT(fraction, 0.05);
        EXPECT_LE(fraction, 0.1);
        const double r = 0.5 * glm::length(k.hi - k.lo);
        // The sphere's silhouette is seen at asin(r / d) off the axis; its image radius, 1/20
        // of the height, is tan of that over tan(fov / 2) in units of half the height.
        const double d = glm::length(c.eye - c.target);
        EXPECT_NEAR(std::tan(std::asin(r / d)) / std::tan(glm::radians(c.fovYDegrees) * 0.5),
                    0.1, 1e-9);
    }
}

TEST(CameraPreset, CloseupLooksAtTheFrontFromOutside) {
    for (const PresetCase& k : kPresetCases) {
        const Camera c = presetCamera(ViewPreset::Closeup, k.lo, k.hi, k.width, k.height);
        const glm::dvec3 centre = (k.lo + k.hi) * 0.5;
        for (int a = 0; a < 3; ++a) {
            EXPECT_GT(c.target[a], k.lo[a]);
            EXPECT_LT(c.target[a], k.hi[a]);
        }
        EXPECT_GT(c.target.y, centre.y);
        EXPECT_GT(c.eye.y, k.hi.y);
        // The view at the target is about 1/6 of the largest extent high.
        const glm::dvec3 e = k.hi - k.lo;
        const double largest = std::max({e.x, e.y, e.z});
        const double viewHeight = 2.0 * glm::length(c.target - c.eye) *
                                  std::tan(glm::radians(c.fovYDegrees) * 0.5);
        EXPECT_NEAR(viewHeight, largest / 6.0, 1e-9 * largest);
        const glm::dvec3 p = c.project(c.target);
        EXPECT_GT(p.z, 0.0);
        EXPECT_LT(p.z, 1.0);
    }
}

TEST(CameraPreset, NamesParse) {
    EXPECT_EQ(parseViewPreset("distant"), ViewPreset::Distant);
    EXPECT_EQ(parseViewPreset("Normal"), ViewPreset::Normal);
    EXPECT_EQ(parseViewPreset("closeup"), ViewPreset::Closeup);
    EXPECT_EQ(parseViewPreset("close-up"), ViewPreset::Closeup);
    for (ViewPreset v : {ViewPreset::Distant, ViewPreset::Normal, ViewPreset::Closeup})
        EXPECT_EQ(parseViewPreset(viewPresetName(v)), v);
    try {
        parseViewPreset("far");
        FAIL() << "no exception";
    } catch (const std::invalid_argument& e) {
        EXPECT_NE(std::string(e.what()).find("'far'"), std::string::npos) << e.what();
    }
}

void expectSameCamera(const Camera& a, const Camera& b) {
    for (int i = 0; i < 3; ++i) {
        EXPECT_EQ(a.eye[i], b.eye[i]);
        EXPECT_EQ(a.target[i], b.target[i]);
        EXPECT_EQ(a.up[i], b.up[i]);
    }
    EXPECT_EQ(a.fovYDegrees, b.fovYDegrees);
    EXPECT_EQ(a.width, b.width);
    EXPECT_EQ(a.height, b.height);
    EXPECT_EQ(a.zNear, b.zNear);
    EXPECT_EQ(a.zFar, b.zFar);
}

TEST(CameraJson, RoundTripsExactly) {
    ScratchDir dir;
    Camera c = presetCamera(ViewPreset::Closeup, {-0.1, 0.3, 1.0 / 3.0}, {255.7, 99.9, 1e3},
                            640, 480);
    for (bool withPlanes : {true, false}) {
        if (!withPlanes) c.zNear = c.zFar = 0.0;
        const std::string path = dir.file(withPlanes ? "a.json" : "b.json");
        test::writeFile(path, cameraToJson(c));
        expectSameCamera(readCameraJson(path, 1, 1), c);
    }
}

TEST(CameraJson, SizeDefaultsToTheCallersAndPathsReadBothForms) {
    ScratchDir dir;
    const std::string one = R"({"eye":[0,-5,1],"target":[0,0,0],"up":[0,0,1],"fov":45})";
    test::writeFile(dir.file("one.json"), one);
    const Camera c = readCameraJson(dir.file("one.json"), 123, 45);
    EXPECT_EQ(c.width, 123);
    EXPECT_EQ(c.height, 45);
    EXPECT_EQ(c.fovYDegrees, 45.0);
    EXPECT_EQ(c.eye.y, -5.0);
    EXPECT_FALSE(c.hasClipPlanes());

    const std::string two =
        R"({"eye":[1,2,3],"target":[0,0,0],"up":[0,0,1],"fov":20,"width":64.0,"height":32,)"
        R"("near":0.5,"far":9})";
    test::writeFile(dir.file("array.json"), "[" + one + ", " + two + "]");
    test::writeFile(dir.file("object.json"), R"({"cameras": [)" + one + ", " + two + "]}");
    for (const char* name : {"array.json", "object.json"}) {
        const std::vector<Camera> path = readCameraPath(dir.file(name), 100, 200);
        ASSERT_EQ(path.size(), 2u);
        EXPECT_EQ(path[0].width, 100);
        EXPECT_EQ(path[1].width, 64);
        EXPECT_EQ(path[1].zNear, 0.5);
        EXPECT_EQ(path[1].zFar, 9.0);
    }
}

std::string cameraError(const std::string& path, bool asPath = false) {
    try {
        if (asPath)
            readCameraPath(path, 80, 80);
        else
            readCameraJson(path, 80, 80);
    } catch (const IoError& e) {
        return e.what();
    }
    return "";
}

TEST(CameraJson, BadFilesNameTheFileAndTheField) {
    ScratchDir dir;
    struct Case {
        const char* text;
        const char* expected;
    };
    const Case cases[] = {
        {"not json at all", "not valid JSON"},
        {"", "not valid JSON"},
        {"[1, 2, 3]", "must be a JSON object"},
        {R"({"target":[0,0,0],"up":[0,0,1],"fov":30})", "'eye' missing"},
        {R"({"eye":"front","target":[0,0,0],"up":[0,0,1],"fov":30})",
         "'eye' must be an array of 3 numbers"},
        {R"({"eye":[1,2],"target":[0,0,0],"up":[0,0,1],"fov":30})",
         "'eye' must be an array of 3 numbers"},
        {R"({"eye":[1,2,"3"],"target":[0,0,0],"up":[0,0,1],"fov":30})",
         "'eye' must be an array of 3 numbers"},
        {R"({"eye":[0,-1,0],"target":[0,0,0],"up":[0,0,1],"fov":"wide"})",
         "'fov' must be a number"},
        {R"({"eye":[0,-1,0],"target":[0,0,0],"up":[0,0,1],"fov":180})", "fov must be in (0, 180)"},
        {R"({"eye":[0,-1,0],"target":[0,0,0],"up":[0,0,1],"fov":30,"width":12.5})",
         "'width' must be a whole number"},
        {R"({"eye":[0,-1,0],"target":[0,0,0],"up":[0,0,1],"fov":30,"width":"64"})",
         "'width' must be a whole number"},
        {R"({"eye":[0,-1,0],"target":[0,0,0],"up":[0,0,1],"fov":30,"height":0})",
         "'height' must be 16 to"},
        {R"({"eye":[0,-1,0],"target":[0,0,0],"up":[0,0,1],"fov":30,"near":1})",
         "'near' and 'far' go together"},
        {R"({"eye":[0,-1,0],"target":[0,0,0],"up":[0,0,1],"fov":30,"near":2,"far":1})",
         "0 < near < far"},
        {R"({"eye":[0,0,0],"target":[0,0,0],"up":[0,0,1],"fov":30})", "must differ"},
        {R"({"eye":[0,0,-1],"target":[0,0,0],"up":[0,0,1],"fov":30})", "up must not be zero"},
        {R"({"eye":[0,-1,0],"target":[0,0,0],"up":[0,0,1],"fovy":30})", "unknown field 'fovy'"},
    };
    for (const Case& k : cases) {
        const std::string path = dir.file("cam.json");
        test::writeFile(path, k.text);
        const std::string message = cameraError(path);
        EXPECT_EQ(message.rfind(path + ": ", 0), 0u) << k.text << " -> " << message;
        EXPECT_NE(message.find(k.expected), std::string::npos) << k.text << " -> " << message;
    }
    EXPECT_NE(cameraError(dir.file("missing.json")).find("cannot open"), std::string::npos);
}

TEST(CameraJson, BadPathsNameTheCamera) {
    ScratchDir dir;
    const std::string good = R"({"eye":[0,-1,0],"target":[0,0,0],"up":[0,0,1],"fov":30})";
    const std::string path = dir.file("path.json");
    test::writeFile(path, R"({"cameras": [)" + good + R"(, {"eye":[0,-1,0]}]})");
    std::string message = cameraError(path, true);
    EXPECT_NE(message.find(path + ": cameras[1]: 'target' missing"), std::string::npos)
        << message;
    test::writeFile(path, "[]");
    EXPECT_NE(cameraError(path, true).find("no cameras"), std::string::npos);
    test::writeFile(path, R"({"views": []})");
    EXPECT_NE(cameraError(path, true).find("must be an array or"), std::string::npos);
    test::writeFile(path, "[" + good + ", 7]");
    message = cameraError(path, true);
    EXPECT_NE(message.find(path + ": [1]: a camera must be a JSON object"), std::string::npos)
        << message;
}

}  // namespace
}  // namespace vdiso

#include "io/camera_json.h"

#include <cerrno>
#include <cmath>
#include <fstream>
#include <sstream>

#include <glm/geometric.hpp>
#include <nlohmann/json.hpp>

#include "io/error.h"
#include "io/json.h"
#include "io/text_file.h"

namespace vdiso {

namespace {

using nlohmann::json;


// A camera path of 16 MiB holds some 80,000 cameras; more is not a camera file.
constexpr size_t kMaxCameraFileBytes = size_t(16) << 20;

std::string readText(const std::string& path) {
    return readBoundedText(path, kMaxCameraFileBytes, "a camera file");
}

json parseJson(const std::string& text, const std::string& name) {
    try {
        return json::parse(text);
    } catch (const json::exception& e) {
        // A syntax error, or a number beyond double's range (1e400: out_of_range.406).
        // Drop nlohmann's "[json.exception.parse_error.101] " tag: it means nothing to users.
        std::string what = e.what();
        if (size_t tagEnd = what.find("] "); what.rfind("[json.", 0) == 0 && tagEnd != what.npos)
            what.erase(0, tagEnd + 2);
        throwIoError(name, "not valid JSON: " + what);
    }
}

// Reads one camera object; `where` is the prefix of its error messages ("cam.json" or
// "path.json: cameras[2]").
class CameraReader {
public:
    CameraReader(const json& object, std::string where)
        : mObject(object), mWhere(std::move(where)) {}

    Camera read(int defaultWidth, int defaultHeight) {
        if (!mObject.is_object()) fail("a camera must be a JSON object");
        for (const auto& item : mObject.items()) {
            static const char* const kKnown[] = {"eye",   "target", "up",   "fov",
                                                 "width", "height", "near", "far"};
            bool known = false;
            for (const char* k : kKnown) known = known || item.key() == k;
            if (!known)
                fail("unknown field '" + item.key() +
                     "' (expected eye, target, up, fov, width, height, near, far)");
        }
        Camera camera;
        camera.eye = vec3("eye");
        camera.target = vec3("target");
        camera.up = vec3("up");
        camera.fovYDegrees = number(required("fov"), "fov");
        camera.width = imageSide("width", defaultWidth);
        camera.height = imageSide("height", defaultHeight);

        const json* n = optional("near");
        const json* f = optional("far");
        if ((n == nullptr) != (f == nullptr)) fail("'near' and 'far' go together");
        if (n) {
            camera.zNear = number(*n, "near");
            camera.zFar = number(*f, "far");
        }

        // The camera as every front end checks one (core/camera.h).
        if (const std::string problem = cameraProblem(camera); !problem.empty()) fail(problem);
        return camera;
    }

private:
    [[noreturn]] void fail(const std::string& message) const { throwIoError(mWhere, message); }

    const json* optional(const char* key) const {
        auto it = mObject.find(key);
        return it == mObject.end() ? nullptr : &*it;
    }
    const json& required(const char* key) const {
        const json* value = optional(key);
        if (!value) fail(std::string("'") + key + "' missing");
        return *value;
    }
    double number(const json& value, const char* key) const {
        if (!value.is_number()) fail(std::string("'") + key + "' must be a number");
        const double x = value.get<double>();
        if (!std::isfinite(x)) fail(std::string("'") + key + "' must be finite");
        return x;
    }
    glm::dvec3 vec3(const char* key) const {
        const json& value = required(key);
        bool ok = value.is_array() && value.size() == 3;
        for (size_t i = 0; ok && i < 3; ++i) ok = value[i].is_number();
        if (!ok) fail(std::string("'") + key + "' must be an array of 3 numbers");
        const glm::dvec3 v{value[0].get<double>(), value[1].get<double>(), value[2].get<double>()};
        if (!std::isfinite(v.x) || !std::isfinite(v.y) || !std::isfinite(v.z))
            fail(std::string("'") + key + "' must be finite");
        return v;
    }
    int imageSide(const char* key, int fallback) const {
        const json* value = optional(key);
        if (!value) return fallback;
        const std::string range = std::to_string(kMinImageSide) + " to " + std::to_string(kMaxImageSide);
        // 800.0 is as good as 800: some writers have only doubles.
        const double side = value->is_number() ? value->get<double>() : 0.5;
        if (side != std::floor(side))
            fail(std::string("'") + key + "' must be a whole number of pixels, " + range);
        if (side < kMinImageSide || side > kMaxImageSide)  // before it is made an int
            fail(std::string("'") + key + "' must be " + range + " pixels");
        return int(side);
    }

    const json& mObject;
    std::string mWhere;
};

}  // namespace

Camera parseCameraJson(const std::string& text, const std::string& name, int defaultWidth,
                       int defaultHeight) {
    return CameraReader(parseJson(text, name), name).read(defaultWidth, defaultHeight);
}

std::vector<Camera> parseCameraPath(const std::string& text, const std::string& name,
                                    int defaultWidth, int defaultHeight) {
    const json document = parseJson(text, name);
    const json* list = &document;
    std::string prefix;
    if (document.is_object()) {
        auto it = document.find("cameras");
        if (it == document.end() || document.size() != 1)
            throwIoError(name, "a camera path must be an array or {\"cameras\": [...]}");
        list = &*it;
        prefix = "cameras";
    }
    if (!list->is_array())
        throwIoError(name, "a camera path must be an array or {\"cameras\": [...]}");
    if (list->empty()) throwIoError(name, "the camera path holds no cameras");
    std::vector<Camera> cameras;
    cameras.reserve(list->size());
    for (size_t i = 0; i < list->size(); ++i) {
        const std::string where = name + ": " + prefix + "[" + std::to_string(i) + "]";
        cameras.push_back(CameraReader((*list)[i], where).read(defaultWidth, defaultHeight));
    }
    return cameras;
}

Camera readCameraJson(const std::string& path, int defaultWidth, int defaultHeight) {
    return parseCameraJson(readText(path), path, defaultWidth, defaultHeight);
}

std::vector<Camera> readCameraPath(const std::string& path, int defaultWidth, int defaultHeight) {
    return parseCameraPath(readText(path), path, defaultWidth, defaultHeight);
}

std::string cameraToJson(const Camera& camera) {
    // nlohmann writes doubles in their shortest round-trip form.
    using ordered = nlohmann::ordered_json;
    auto array = [](const glm::dvec3& v) { return ordered::array({v.x, v.y, v.z}); };
    ordered object = ordered::object();
    object["eye"] = array(camera.eye);
    object["target"] = array(camera.target);
    object["up"] = array(camera.up);
    object["fov"] = camera.fovYDegrees;
    object["width"] = camera.width;
    object["height"] = camera.height;
    if (camera.hasClipPlanes()) {
        object["near"] = camera.zNear;
        object["far"] = camera.zFar;
    }
    return object.dump();
}

}  // namespace vdiso

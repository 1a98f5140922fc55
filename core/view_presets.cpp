#include "core/view_presets.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <stdexcept>

#include <glm/geometric.hpp>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/matrix.hpp>
#include <glm/trigonometric.hpp>

namespace vdiso {

namespace {

const glm::dvec3 kPresetViewDirection = glm::normalize(glm::dvec3(0.35, 1.0, 0.3));
const glm::dvec3 kPresetUp{0.0, 0.0, 1.0};
constexpr double kPresetFovYDegrees = 30.0;
constexpr double kDistantImageFraction = 0.1;  // sphere diameter / image height
constexpr double kCloseupLookAtFront = 0.35;   // of e.y in front of the centre
constexpr double kCloseupFraction = 1.0 / 6.0; // of max(e), the view height at the target

}  // namespace

ViewFacing defaultFacing() {
    ViewFacing f;
    f.toEye = kPresetViewDirection;
    f.up = kPresetUp;
    f.front = {0.0, 1.0, 0.0};
    return f;
}

ViewFacing patientFacing(PatientSide side, const glm::dmat3& direction) {
    // The side's direction from the patient towards the eye, and up, in LPS.
    const glm::dvec3 anterior{0.0, -1.0, 0.0}, superior{0.0, 0.0, 1.0}, left{1.0, 0.0, 0.0};
    glm::dvec3 toEye, up = superior;
    switch (side) {
    case PatientSide::Anterior: toEye = anterior; break;
    case PatientSide::Posterior: toEye = -anterior; break;
    case PatientSide::Left: toEye = left; break;
    case PatientSide::Right: toEye = -left; break;
    case PatientSide::Superior: toEye = superior; up = anterior; break;
    case PatientSide::Inferior: toEye = -superior; up = anterior; break;
    }
    // Volume space differs from physical space by D about the origin: a physical direction v is
    // D^-1 v in volume space.
    const glm::dmat3 toVolume = glm::inverse(direction);
    ViewFacing f;
    f.toEye = glm::normalize(toVolume * toEye);
    f.up = glm::normalize(toVolume * up);  // unit even where the direction shears
    f.front = f.toEye;
    return f;
}

ViewFacing viewFacing(const std::optional<PatientSide>& side, const VolumeInfo& volume) {
    if (!volume.hasOrientation) {
        if (side)
            throw std::invalid_argument(
                std::string("the view '") + patientSideName(*side) +
                "' needs a volume with an orientation, and this one has none (its input file "
                "gave none, or it was converted before store format 4); use distant, normal or "
                "closeup");
        return defaultFacing();
    }
    return patientFacing(side.value_or(PatientSide::Anterior), volume.direction);
}

Camera presetCamera(ViewPreset preset, const glm::dvec3& boundsMin, const glm::dvec3& boundsMax,
                    int width, int height) {
    return presetCamera(preset, defaultFacing(), boundsMin, boundsMax, width, height);
}

Camera presetCamera(ViewPreset preset, const ViewFacing& facing, const glm::dvec3& boundsMin,
                    const glm::dvec3& boundsMax, int width, int height, double times) {
    if (width <= 0 || height <= 0)
        throw std::invalid_argument("presetCamera: image size must be positive");
    Camera camera;
    camera.width = width;
    camera.height = height;
    camera.up = facing.up;
    camera.fovYDegrees = kPresetFovYDegrees;

    const glm::dvec3 centre = (boundsMin + boundsMax) * 0.5;
    const glm::dvec3 extent = boundsMax - boundsMin;
    // A flat or empty volume still gets a camera at a sensible distance.
    const double radius = std::max(0.5 * glm::length(extent), 1e-6);
    const double tanHalfFovY = std::tan(glm::radians(camera.fovYDegrees) * 0.5);
    // The narrower of the two half-angles bounds what fits in the image.
    const double halfFit = std::atan(tanHalfFovY * std::min(1.0, camera.aspect()));

    double distance = 0.0;
    camera.target = centre;
    switch (preset) {
    case ViewPreset::Normal:
        distance = radius / std::sin(halfFit);
        break;
    case ViewPreset::Distant:
        // The sphere's silhouette has angular radius asin(r / d); its image radius in NDC is
        // tan of that over tanHalfFovY.
        distance = radius / std::sin(std::atan(kDistantImageFraction * tanHalfFovY));
        break;
    case ViewPreset::Closeup: {
        // The bounds' depth along the front direction (e.y for the default +y).
        const glm::dvec3 f = facing.front;
        const double depth = std::abs(f.x) * extent.x + std::abs(f.y) * extent.y + std::abs(f.z) * extent.z;
        camera.target = centre + f * (kCloseupLookAtFront * depth);
        const double largest = std::max({extent.x, extent.y, extent.z, 1e-6});
        distance = 0.5 * kCloseupFraction * largest / tanHalfFovY;
        break;
    }
    }
    camera.eye = camera.target + facing.toEye * (distance * times);
    fitClipPlanes(camera, boundsMin, boundsMax);
    return camera;
}

namespace {

std::string lowerCase(const std::string& text) {
    std::string lower;
    for (char c : text) lower += char(std::tolower(static_cast<unsigned char>(c)));
    return lower;
}

}  // namespace

ViewPreset parseViewPreset(const std::string& name) {
    const std::string lower = lowerCase(name);
    if (lower == "distant") return ViewPreset::Distant;
    if (lower == "normal") return ViewPreset::Normal;
    if (lower == "closeup" || lower == "close-up") return ViewPreset::Closeup;
    throw std::invalid_argument("unknown view '" + name +
                                "' (expected distant, normal or closeup)");
}

const char* viewPresetName(ViewPreset preset) {
    switch (preset) {
    case ViewPreset::Distant: return "distant";
    case ViewPreset::Normal: return "normal";
    case ViewPreset::Closeup: return "closeup";
    }
    return "?";
}

std::optional<PatientSide> parsePatientSide(const std::string& name) {
    const std::string lower = lowerCase(name);
    for (PatientSide side : {PatientSide::Anterior, PatientSide::Posterior, PatientSide::Left,
                             PatientSide::Right, PatientSide::Superior, PatientSide::Inferior})
        if (lower == patientSideName(side)) return side;
    return std::nullopt;
}

const char* patientSideName(PatientSide side) {
    switch (side) {
    case PatientSide::Anterior: return "anterior";
    case PatientSide::Posterior: return "posterior";
    case PatientSide::Left: return "left";
    case PatientSide::Right: return "right";
    case PatientSide::Superior: return "superior";
    case PatientSide::Inferior: return "inferior";
    }
    return "?";
}

ViewChoice parseViewChoice(const std::string& text) {
    const auto refuse = [&] {
        throw std::invalid_argument(
            "unknown view '" + text +
            "' (expected a distance: distant, normal, closeup or a multiple of the normal one "
            "such as 2.5; a side: anterior, posterior, "
            "left, right, superior or inferior; or a distance and a side, as closeup,anterior)");
    };
    ViewChoice choice;
    bool distanceGiven = false;
    size_t start = 0;
    for (int part = 0; start <= text.size(); ++part) {
        const size_t comma = text.find(',', start);
        const std::string word = text.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
        if (part > 1) refuse();
        if (const std::optional<PatientSide> side = parsePatientSide(word)) {
            if (choice.side) refuse();
            choice.side = side;
        } else {
            if (distanceGiven) refuse();
            try {
                choice.distance = parseViewPreset(word);
            } catch (const std::invalid_argument&) {
                char* end = nullptr;
                const double times = word.empty() ? 0.0 : std::strtod(word.c_str(), &end);
                if (end != word.c_str() + word.size() || !(times > 0.0) || !std::isfinite(times)) refuse();
                choice.distance = ViewPreset::Normal;
                choice.times = times;
            }
            distanceGiven = true;
        }
        if (comma == std::string::npos) break;
        start = comma + 1;
    }
    return choice;
}

std::string viewChoiceName(const ViewChoice& choice) {
    std::string name = viewPresetName(choice.distance);
    if (choice.distance == ViewPreset::Normal && choice.times != 1.0) {
        char text[32];
        std::snprintf(text, sizeof text, "%g", choice.times);
        name = text;
    }
    if (choice.side) name += std::string(",") + patientSideName(*choice.side);
    return name;
}

std::vector<Camera> orbitCameras(ViewPreset preset, const glm::dvec3& boundsMin,
                                 const glm::dvec3& boundsMax, int width, int height, int frames) {
    return orbitCameras(preset, defaultFacing(), boundsMin, boundsMax, width, height, frames);
}

std::vector<Camera> orbitCameras(ViewPreset preset, const ViewFacing& facing,
                                 const glm::dvec3& boundsMin, const glm::dvec3& boundsMax,
                                 int width, int height, int frames, double times) {
    const Camera base = presetCamera(preset, facing, boundsMin, boundsMax, width, height, times);
    const glm::dvec3 axis = glm::normalize(facing.up);
    std::vector<Camera> cameras;
    for (int k = 0; k < frames; ++k) {
        const double angle = 2.0 * 3.14159265358979323846 * double(k) / double(frames);
        const double c = std::cos(angle), s = std::sin(angle);
        Camera camera = base;
        // Rodrigues' rotation about the axis, the part along it kept exactly (about +z this is
        // (c x - s y, s x + c y, z), bit for bit).
        const glm::dvec3 offset = base.eye - base.target;
        const glm::dvec3 along = axis * glm::dot(axis, offset);
        const glm::dvec3 across = offset - along;
        camera.eye = base.target + (along + across * c + glm::cross(axis, offset) * s);
        fitClipPlanes(camera, boundsMin, boundsMax);
        cameras.push_back(camera);
    }
    return cameras;
}

}  // namespace vdiso

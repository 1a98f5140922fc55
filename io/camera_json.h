// Cameras in JSON files.
//
// One camera is an object:
//   {"eye": [x,y,z], "target": [x,y,z], "up": [x,y,z], "fov": 30,
//    "width": 800, "height": 600, "near": 0.1, "far": 1000}
// eye, target, up (world units) and fov (vertical, degrees) are required; width and height
// default to the caller's values; near and far are optional (0 < near < far, both or neither;
// without them the clip planes are derived later, see core/camera.h). The camera must pass
// core/camera.h's cameraProblem (fov in (0, 180), sides of kMinImageSide to kMaxImageSide, eye
// within kMaxEyeDistance of target, ...). Unknown fields are errors, so that a misspelt
// "fovy" does not silently do nothing.
// A camera path is a JSON array of such objects, or {"cameras": [...]}, with at least one.
// A camera file holds at most 16 MiB; a larger or endless one (/dev/zero) is refused after
// reading that much.
//
// Errors throw IoError naming the file, where in it, and what is wrong
// ("cam.json: 'eye' must be an array of 3 numbers", "path.json: cameras[2]: 'fov' missing").
#pragma once

#include <string>
#include <vector>

#include "core/camera.h"

namespace vdiso {

Camera readCameraJson(const std::string& path, int defaultWidth, int defaultHeight);
std::vector<Camera> readCameraPath(const std::string& path, int defaultWidth, int defaultHeight);

// The same, from JSON text; `name` stands for the file in error messages.
Camera parseCameraJson(const std::string& text, const std::string& name, int defaultWidth,
                       int defaultHeight);
std::vector<Camera> parseCameraPath(const std::string& text, const std::string& name,
                                    int defaultWidth, int defaultHeight);

// One camera as a one-line JSON object that the readers accept, with every double written so
// that it reads back bit-exactly. near and far are written only when set (hasClipPlanes()).
std::string cameraToJson(const Camera& camera);

}  // namespace vdiso

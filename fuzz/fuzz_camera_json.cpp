// Camera and camera-path JSON (--camera, --path).
#include <string>

#include "fuzz/fuzz_input.h"
#include "io/camera_json.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    const std::string text(reinterpret_cast<const char*>(data), size);
    vdiso::fuzz::expectAnswer([&] { vdiso::parseCameraJson(text, "cam.json", 800, 600); });
    vdiso::fuzz::expectAnswer([&] { vdiso::parseCameraPath(text, "path.json", 800, 600); });
    return 0;
}

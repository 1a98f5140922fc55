#include "app/view_camera.h"

#include <stdexcept>

#include "app/extract_settings.h"
#include "core/view_presets.h"

namespace vdiso {

ViewFacing chooseFacing(ViewChoice& choice, const VolumeInfo& volume) {
    ViewFacing facing;
    try {
        facing = viewFacing(choice.side, volume);
    } catch (const std::invalid_argument& e) {
        throw SettingsError("view", viewChoiceName(choice) + ": " + e.what());
    }
    if (!choice.side && volume.hasOrientation) choice.side = PatientSide::Anterior;
    return facing;
}

Camera viewCamera(ViewChoice& choice, const VolumeInfo& volume, int width, int height) {
    const ViewFacing facing = chooseFacing(choice, volume);
    Camera camera = presetCamera(choice.distance, facing, volume.origin, volume.worldMax(), width, height,
                                 choice.times);
    fitClipPlanes(camera, volume);
    return camera;
}

void fitClipPlanes(Camera& camera, const VolumeInfo& volume) {
    if (!camera.hasClipPlanes()) fitClipPlanes(camera, volume.origin, volume.worldMax());
}

}  // namespace vdiso

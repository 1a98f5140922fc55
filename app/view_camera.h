// The camera of a named view (--view, the Python module's view=): a preset distance from a side
// of the volume, framed on its world bounds, with clip planes fitted to them.
#pragma once

#include "core/camera.h"
#include "core/view_presets.h"
#include "core/volume.h"

namespace vdiso {

// The facing of `choice` on `volume` (core/camera.h viewFacing); `choice` gets the side a volume
// with orientation defaults to (anterior), for reports. Throws SettingsError("view") for a side
// on a volume without orientation.
ViewFacing chooseFacing(ViewChoice& choice, const VolumeInfo& volume);

// The preset camera of `choice` (chooseFacing), clip planes fitted.
Camera viewCamera(ViewChoice& choice, const VolumeInfo& volume, int width, int height);

// Sets clip planes around the volume's bounds unless the camera has its own.
void fitClipPlanes(Camera& camera, const VolumeInfo& volume);

}  // namespace vdiso

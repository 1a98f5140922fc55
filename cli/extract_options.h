// vdiso extract's options: parsed once for vdiso and for vdiso-mpi, which takes the same
// command line under mpirun, and the cameras they ask for.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "app/extract_settings.h"
#include "core/camera.h"
#include "core/extract/extract_view.h"
#include "core/view_presets.h"
#include "core/volume.h"
#include "io/remote/remote_options.h"

namespace vdiso::cli {

// The text of 'vdiso extract --help'.
extern const char* const kExtractHelp;

// The extraction's settings (app/extract_settings.h) and what the command line adds: the store,
// the outputs, the cameras.
struct ExtractOptions : ExtractSettings {
    std::string input;
    std::string pointsPath;
    bool oracle = false;
    int orbitFrames = 0;   // --path orbit:N
    std::string pathFile;  // --path FILE.json
    std::string meshPath, pngPath, statsPath, cameraPath;
    ViewChoice view;
    bool viewGiven = false;
    int width = kDefaultImageWidth, height = kDefaultImageHeight;
    RemoteOptions remote;  // for a store at a URL
    bool overwrite = false, quiet = false, cold = false, help = false;
    bool meshCompress = false;  // --mesh-compress (.glb only)
};

// Parses vdiso extract's arguments (argv[0] is "extract") and checks them against each other;
// throws UsageError. With --help or -h, returns at once with `help` set.
ExtractOptions parseExtractOptions(int argc, char** argv);

// The cameras the options ask for over `volume`: one (--camera, --view or its default), the
// frames of a --path, or none (a full method without a picture); each with its clip planes.
// `view`: the preset used, with the side a store with orientation defaults to.
std::vector<Camera> extractCameras(const ExtractOptions& o, const VolumeInfo& volume, ViewChoice& view);

}  // namespace vdiso::cli

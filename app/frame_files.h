// The files of one frame, as vdiso extract and vdiso-mpi extract write them: the mesh (-o, any
// mesh format), the sub-pixel points (--points-out, PLY), both mapped by `transform`, and the
// picture (--png) drawn from `camera` (io/render/renderer.h). Each is refused when it exists
// and `overwrite` is off (io/mesh/mesh_writer.h); an empty path writes nothing.
#pragma once

#include <optional>
#include <string>

#include "core/camera.h"
#include "core/mesh.h"
#include "core/orientation.h"

namespace vdiso {

struct FrameFiles {
    std::string mesh, points, png;
    bool overwrite = false;
    bool compressMesh = false;  // .glb only (EXT_meshopt_compression)
};

// Writes them; returns the drawing's seconds when a picture was drawn. A picture needs a
// camera (std::invalid_argument without one).
std::optional<double> writeFrameFiles(const FrameFiles& files, const TriangleMesh& mesh, const PointSet& points,
                                      const Camera* camera, const SpaceTransform& transform);

}  // namespace vdiso

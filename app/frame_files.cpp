#include "app/frame_files.h"

#include <stdexcept>

#include "io/mesh/mesh_writer.h"
#include "io/render/png_image.h"
#include "io/render/renderer.h"

namespace vdiso {

std::optional<double> writeFrameFiles(const FrameFiles& files, const TriangleMesh& mesh, const PointSet& points,
                                      const Camera* camera, const SpaceTransform& transform) {
    if (!files.mesh.empty()) writeMesh(files.mesh, mesh, files.overwrite, files.compressMesh, transform);
    if (!files.points.empty()) writePointsPly(files.points, points, files.overwrite, transform);
    if (files.png.empty()) return std::nullopt;
    if (!camera) throw std::invalid_argument(files.png + ": a picture needs a camera");
    const RenderResult picture = renderSurface(mesh, points, *camera);
    writePng(files.png, picture.image, files.overwrite);
    return picture.drawSeconds;
}

}  // namespace vdiso

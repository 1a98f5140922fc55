// The OpenVDB reader module (see vdb_module.h): a float or double grid as a dense volume.
//
// A grid chosen by name (empty: the first float or double grid); its active-voxel bounding
// box becomes the volume's extent, inactive voxels take the grid's background value, the
// voxel size gives the spacing and the box's world position the origin.
#include "io/readers/vdb_module/vdb_module.h"

#include <algorithm>
#include <cstring>
#include <exception>
#include <string>
#include <variant>

#include <openvdb/io/File.h>
#include <openvdb/openvdb.h>
#include <openvdb/tools/Dense.h>

namespace {

// Why the file cannot be read; becomes the host's IoError, prefixed with the path there.
struct Failure {
    std::string message;
};

using GridPtr = std::variant<openvdb::FloatGrid::ConstPtr, openvdb::DoubleGrid::ConstPtr>;

struct OpenGrid {
    GridPtr grid;
    openvdb::CoordBBox box;
};

bool isConvertible(const openvdb::GridBase& grid) {
    return grid.isType<openvdb::FloatGrid>() || grid.isType<openvdb::DoubleGrid>();
}

std::string quoted(const std::string& name) {
    return "'" + name + "'";
}

// "'density' (float), 'v' (vec3s)": what the file offers, for messages that must say what to ask
// for instead.
std::string describeGrids(const openvdb::GridPtrVec& grids) {
    if (grids.empty()) return "no grids";
    std::string list;
    for (const openvdb::GridBase::Ptr& g : grids) {
        if (!list.empty()) list += ", ";
        list += quoted(g->getName()) + " (" + g->valueType() + ")";
    }
    return list;
}

// Picks the grid by name (empty: the first float or double grid) from the metadata alone, so
// that only the chosen grid's voxels are ever loaded.
openvdb::GridBase::Ptr chooseGrid(const openvdb::GridPtrVec& grids, const std::string& gridName) {
    for (const openvdb::GridBase::Ptr& g : grids) {
        if (gridName.empty() ? isConvertible(*g) : g->getName() == gridName) return g;
    }
    if (gridName.empty()) throw Failure{"no float or double grid; the file holds " + describeGrids(grids)};
    throw Failure{"no grid named " + quoted(gridName) + "; the file holds " + describeGrids(grids)};
}

void requireConvertible(const openvdb::GridBase& grid) {
    if (!isConvertible(grid))
        throw Failure{"grid " + quoted(grid.getName()) + " holds " + grid.valueType() +
                      " values; only float and double grids can be converted"};
}

// A dense volume has axis-aligned, evenly spaced samples; a rotated or frustum transform would
// be silently misplaced.
void requireAxisAligned(const openvdb::GridBase& grid) {
    const openvdb::math::Transform& t = grid.transform();
    if (!t.isLinear() || !t.baseMap()->getAffineMap()->isScaleTranslate())
        throw Failure{"grid " + quoted(grid.getName()) + " has a " + t.mapType() +
                      " transform; only axis-aligned voxels can be converted"};
}

openvdb::GridBase::Ptr loadGrid(const std::string& path, const std::string& gridName) {
    openvdb::io::File file(path);
    try {
        // No delayed loading: a truncated file should fail here, not halfway through a slab.
        file.open(false);
    } catch (const openvdb::Exception& e) {
        throw Failure{std::string("not an OpenVDB file (") + e.what() + ")"};
    }
    const openvdb::GridPtrVecPtr metadata = file.readAllGridMetadata();
    const openvdb::GridBase::Ptr chosen = chooseGrid(*metadata, gridName);
    requireConvertible(*chosen);
    openvdb::GridBase::Ptr grid = file.readGrid(chosen->getName());
    file.close();
    // Several grids may share a name; the one read must still be a float grid.
    requireConvertible(*grid);
    return grid;
}

OpenGrid* openGrid(const std::string& path, const std::string& gridName, VdisoVdbVolume& volume) {
    openvdb::initialize();
    const openvdb::GridBase::Ptr grid = loadGrid(path, gridName);
    requireAxisAligned(*grid);
    const openvdb::CoordBBox box = grid->evalActiveVoxelBoundingBox();
    const std::string label = "grid " + quoted(grid->getName());
    if (box.empty()) throw Failure{label + " has no active voxels"};
    const openvdb::Coord extent = box.dim();
    for (int a = 0; a < 3; ++a)
        if (extent[a] < 2)
            throw Failure{label + "'s active voxels span " + std::to_string(extent.x()) + " x " +
                          std::to_string(extent.y()) + " x " + std::to_string(extent.z()) +
                          "; every axis needs at least 2 samples"};
    const openvdb::Vec3d spacing = grid->voxelSize();
    const openvdb::Vec3d origin = grid->indexToWorld(box.min());
    for (int a = 0; a < 3; ++a) {
        volume.dims[a] = extent[a];
        volume.spacing[a] = spacing[a];
        volume.origin[a] = origin[a];
    }
    auto* open = new OpenGrid{};
    open->box = box;
    if (grid->isType<openvdb::FloatGrid>())
        open->grid = openvdb::gridConstPtrCast<openvdb::FloatGrid>(grid);
    else
        open->grid = openvdb::gridConstPtrCast<openvdb::DoubleGrid>(grid);
    return open;
}

void fail(const std::string& message, char* err, size_t errBytes) {
    if (errBytes == 0) return;
    const size_t n = std::min(message.size(), errBytes - 1);
    std::memcpy(err, message.data(), n);
    err[n] = '\0';
}

}  // namespace

extern "C" {

__attribute__((visibility("default"))) void* vdiso_vdb_open(const char* path, const char* grid,
                                                            VdisoVdbVolume* volume, char* err,
                                                            size_t errBytes) {
    try {
        return openGrid(path, grid, *volume);
    } catch (const Failure& f) {
        fail(f.message, err, errBytes);
    } catch (const std::exception& e) {  // openvdb::Exception and the rest
        fail(e.what(), err, errBytes);
    }
    return nullptr;
}

__attribute__((visibility("default"))) int vdiso_vdb_read(void* handle, int64_t firstSlice,
                                                         int64_t count, float* dst, char* err,
                                                         size_t errBytes) {
    const OpenGrid& open = *static_cast<const OpenGrid*>(handle);
    try {
        // Only the slab's sub-box goes dense; copyToDense writes every voxel of it, inactive
        // ones included (as the tree's value there, the background outside any tile).
        const openvdb::Coord lo = open.box.min().offsetBy(0, 0, int32_t(firstSlice));
        const openvdb::Coord hi(open.box.max().x(), open.box.max().y(), lo.z() + int32_t(count) - 1);
        openvdb::tools::Dense<float, openvdb::tools::LayoutXYZ> slab(openvdb::CoordBBox(lo, hi), dst);
        std::visit([&](const auto& grid) { openvdb::tools::copyToDense(*grid, slab); }, open.grid);
        return 0;
    } catch (const std::exception& e) {
        fail(e.what(), err, errBytes);
    }
    return -1;
}

__attribute__((visibility("default"))) void vdiso_vdb_close(void* handle) {
    delete static_cast<OpenGrid*>(handle);
}

}  // extern "C"

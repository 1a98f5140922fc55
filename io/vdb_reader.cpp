#include "io/vdb_reader.h"

#include <cerrno>
#include <cstdio>
#include <variant>

#include <openvdb/io/File.h>
#include <openvdb/openvdb.h>
#include <openvdb/tools/Dense.h>

#include "io/error.h"

namespace vdiso {
namespace {

using GridPtr = std::variant<openvdb::FloatGrid::ConstPtr, openvdb::DoubleGrid::ConstPtr>;

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
openvdb::GridBase::Ptr chooseGrid(const std::string& path, const openvdb::GridPtrVec& grids,
                                  const std::string& gridName) {
    for (const openvdb::GridBase::Ptr& g : grids) {
        if (gridName.empty() ? isConvertible(*g) : g->getName() == gridName) return g;
    }
    if (gridName.empty())
        throwIoError(path, "no float or double grid; the file holds " + describeGrids(grids));
    throwIoError(path,
                 "no grid named " + quoted(gridName) + "; the file holds " + describeGrids(grids));
}

void requireConvertible(const std::string& path, const openvdb::GridBase& grid) {
    if (!isConvertible(grid))
        throwIoError(path, "grid " + quoted(grid.getName()) + " holds " + grid.valueType() +
                               " values; only float and double grids can be converted");
}

// A dense volume has axis-aligned, evenly spaced samples; a rotated or frustum transform would
// be silently misplaced.
void requireAxisAligned(const std::string& path, const openvdb::GridBase& grid) {
    const openvdb::math::Transform& t = grid.transform();
    if (!t.isLinear() || !t.baseMap()->getAffineMap()->isScaleTranslate())
        throwIoError(path, "grid " + quoted(grid.getName()) + " has a " + t.mapType() +
                               " transform; only axis-aligned voxels can be converted");
}

openvdb::GridBase::Ptr loadGrid(const std::string& path, const std::string& gridName) {
    openvdb::io::File file(path);
    try {
        // No delayed loading: a truncated file should fail here, not halfway through a slab.
        file.open(false);
    } catch (const openvdb::Exception& e) {
        throwIoError(path, std::string("not an OpenVDB file (") + e.what() + ")");
    }
    const openvdb::GridPtrVecPtr metadata = file.readAllGridMetadata();
    const openvdb::GridBase::Ptr chosen = chooseGrid(path, *metadata, gridName);
    requireConvertible(path, *chosen);
    openvdb::GridBase::Ptr grid = file.readGrid(chosen->getName());
    file.close();
    // Several grids may share a name; the one read must still be a float grid.
    requireConvertible(path, *grid);
    return grid;
}

GridPtr typedGrid(const openvdb::GridBase::Ptr& grid) {
    if (grid->isType<openvdb::FloatGrid>())
        return openvdb::gridConstPtrCast<openvdb::FloatGrid>(grid);
    return openvdb::gridConstPtrCast<openvdb::DoubleGrid>(grid);
}

class VdbSliceReader final : public SliceReader {
public:
    VdbSliceReader(const std::string& path, const std::string& gridName) : mPath(path) {
        requireReadable(path);
        openvdb::initialize();
        try {
            open(gridName);
        } catch (const openvdb::Exception& e) {
            throwIoError(path, e.what());
        }
    }

    const VolumeInfo& info() const override { return mInfo; }

    void read(void* dst, int64_t count) override {
        if (count < 0 || mNextZ + count > mInfo.dims[2])
            throwIoError(mPath, "read of " + std::to_string(count) + " slices from slice " +
                                    std::to_string(mNextZ) + " runs past the grid's " +
                                    std::to_string(mInfo.dims[2]));
        if (count == 0) return;
        // Only the slab's sub-box goes dense; copyToDense writes every voxel of it, inactive
        // ones included (as the tree's value there, the background outside any tile).
        const openvdb::Coord lo = mBox.min().offsetBy(0, 0, int32_t(mNextZ));
        const openvdb::Coord hi(mBox.max().x(), mBox.max().y(), lo.z() + int32_t(count) - 1);
        openvdb::tools::Dense<float, openvdb::tools::LayoutXYZ> slab(openvdb::CoordBBox(lo, hi),
                                                                     static_cast<float*>(dst));
        try {
            std::visit([&](const auto& grid) { openvdb::tools::copyToDense(*grid, slab); }, mGrid);
        } catch (const openvdb::Exception& e) {
            throwIoError(mPath, e.what());
        }
        mNextZ += count;
    }

    std::string name() const override { return mPath; }

private:
    static void requireReadable(const std::string& path) {
        std::FILE* f = std::fopen(path.c_str(), "rb");
        if (!f) throwSystemError(path, "cannot open", errno);
        std::fclose(f);
    }

    void open(const std::string& gridName) {
        const openvdb::GridBase::Ptr grid = loadGrid(mPath, gridName);
        requireAxisAligned(mPath, *grid);
        mBox = grid->evalActiveVoxelBoundingBox();
        const std::string label = "grid " + quoted(grid->getName());
        if (mBox.empty()) throwIoError(mPath, label + " has no active voxels");
        const openvdb::Coord extent = mBox.dim();
        for (int a = 0; a < 3; ++a) {
            if (extent[a] < 2)
                throwIoError(mPath, label + "'s active voxels span " + std::to_string(extent.x()) +
                                        " x " + std::to_string(extent.y()) + " x " +
                                        std::to_string(extent.z()) +
                                        "; every axis needs at least 2 samples");
        }
        mInfo.dims = {extent.x(), extent.y(), extent.z()};
        mInfo.type = ScalarType::F32;
        const openvdb::Vec3d spacing = grid->voxelSize();
        const openvdb::Vec3d origin = grid->indexToWorld(mBox.min());
        mInfo.spacing = {spacing.x(), spacing.y(), spacing.z()};
        mInfo.origin = {origin.x(), origin.y(), origin.z()};
        mGrid = typedGrid(grid);
    }

    std::string mPath;
    VolumeInfo mInfo;
    GridPtr mGrid;
    openvdb::CoordBBox mBox;
    int64_t mNextZ = 0;
};

}  // namespace

std::unique_ptr<SliceReader> openVdbVolume(const std::string& path, const std::string& gridName) {
    return std::make_unique<VdbSliceReader>(path, gridName);
}

}  // namespace vdiso

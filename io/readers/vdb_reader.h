// OpenVDB grids as dense volumes.
//
// A float or double grid chosen by name (empty: the first float or double grid); its
// active-voxel bounding box becomes the volume's extent, inactive voxels take the grid's
// background value, the voxel size gives the spacing and the box's world position the origin.
// The reading is done by the module libvdiso_vdb.so (io/readers/vdb_module/), loaded on first use, so
// that no other command pays for linking OpenVDB.
#pragma once

#include <memory>
#include <string>

#include "io/readers/slice_reader.h"

namespace vdiso {

std::unique_ptr<SliceReader> openVdbVolume(const std::string& path, const std::string& gridName);

}  // namespace vdiso

// A store index's level 0 kept where it lies (vdiso index): the record, inside the index file,
// of the Zarr array that holds level 0's samples and of what pins them (docs/store-format.md,
// "Indexes of data kept elsewhere"). Level 0's index entries say "external" and have no bytes
// in the file; io/store/external_bricks.h assembles those bricks from the array's chunks.
//
//   "VDISOEXT" u32 version (1) u32 jsonBytes [JSON] u64 chunkCount [chunkCount x (u64 bytes,
//   u32 crc)] u32 CRC-32 of everything before it
//
// The JSON says where the array is ("location": a URL, an absolute path, or a path relative to
// the index file's folder), which OME-Zarr level ("level"), its metadata's CRC-32
// ("metadata_crc"), its chunk shape and counts (x, y, z). The pins are every chunk's, x fastest
// (io/readers/zarr_reader.h ZarrChunkPin).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "core/volume.h"
#include "io/readers/zarr_reader.h"

namespace vdiso {

struct ExternalLevel {
    std::string location;
    int level = 0;
    uint32_t metadataCrc = 0;
    Dims3 chunkShape{}, chunkCounts{};
    std::vector<ZarrChunkPin> pins;
};

std::vector<unsigned char> encodeExternalLevel(const ExternalLevel& external);

// Throws IoError naming `path` (the index file) when the record is damaged or inconsistent.
ExternalLevel decodeExternalLevel(const unsigned char* bytes, size_t n, const std::string& path);

// Where the array is, for an index at `indexPath`: a relative location is taken from the index
// file's folder (a URL's or an absolute path is kept).
std::string resolveExternalLocation(const std::string& location, const std::string& indexPath);

// What an index at `indexPath` records for an array at `dataPath`: a URL as given (without its
// query), a local path relative to the index's folder when the index is local too, else absolute.
std::string externalLocationFor(const std::string& dataPath, const std::string& indexPath);

// The index beside a dataset by default: "DATA.vdiso" (a trailing slash dropped).
std::string defaultIndexPath(const std::string& dataPath);

}  // namespace vdiso

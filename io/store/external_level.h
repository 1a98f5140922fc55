// The levels of a store index kept where they lie (vdiso index): the record, inside the index
// file, of the Zarr arrays that hold their samples and of what pins them (docs/store-format.md,
// "Indexes of data kept elsewhere"). Level 0 always lies there; a coarser level does when the
// index takes it from an OME-Zarr's own multiscales. Those levels' index entries say
// "external" and have no bytes in the file; io/store/external_bricks.h assembles their bricks
// from the arrays' chunks. The levels that lie elsewhere are the store's first ones: the
// record's i-th is the store's level i.
//
//   version 1 (level 0 only): "VDISOEXT" u32 1 [level] u32 CRC-32 of everything before it
//   version 2: "VDISOEXT" u32 2 u32 levels [level]... u32 CRC-32 of everything before it
//   [level]: u32 jsonBytes [JSON] u64 chunkCount [chunkCount x (u64 bytes, u32 crc)]
//
// A level's JSON says where its array is ("location": a URL, an absolute path, or a path
// relative to the index file's folder), which OME-Zarr level ("level"), its metadata's CRC-32
// ("metadata_crc"), its chunk shape and counts (x, y, z). The pins are every chunk's, x fastest
// (io/readers/zarr_reader.h ZarrChunkPin). Version 1 is written when only level 0 lies
// elsewhere, so that such indexes open in builds before version 2.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "core/volume.h"
#include "io/readers/zarr_reader.h"

namespace vdiso {

// How many samples a coarser level's array may be short of its level's dims on an axis (a scale
// of every other sample, ceil(n / 2) long, is one short of level 1 on an even axis): the index
// clamps it at its last sample.
constexpr int kScaleSamplesShort = 2;

struct ExternalLevel {
    std::string location;
    int level = 0;  // the OME-Zarr level (multiscales dataset) read
    uint32_t metadataCrc = 0;
    Dims3 chunkShape{}, chunkCounts{};
    std::vector<ZarrChunkPin> pins;
};

// The record of `levels` (the store's levels 0, 1, ...; at least one).
std::vector<unsigned char> encodeExternalLevels(const std::vector<ExternalLevel>& levels);

// Throws IoError naming `path` (the index file) when the record is damaged or inconsistent.
std::vector<ExternalLevel> decodeExternalLevels(const unsigned char* bytes, size_t n, const std::string& path);

// Where the array is, for an index at `indexPath`: a relative location is taken from the index
// file's folder (a URL's or an absolute path is kept).
std::string resolveExternalLocation(const std::string& location, const std::string& indexPath);

// What an index at `indexPath` records for an array at `dataPath`: a URL as given (without its
// query), a local path relative to the index's folder when the index is local too, else absolute.
std::string externalLocationFor(const std::string& dataPath, const std::string& indexPath);

// The index beside a dataset by default: "DATA.vdiso" (a trailing slash dropped).
std::string defaultIndexPath(const std::string& dataPath);

}  // namespace vdiso

// CRC-32 (zlib's polynomial) of a byte range: the checksum of a store's header, index and
// bricks (io/store/store_format.h), and of the ranges a remote store's disk cache keeps
// (io/remote/disk_cache.h). A header of its own so that neither includes the other.
#pragma once

#include <cstddef>
#include <cstdint>

namespace vdiso {

uint32_t crc32Of(const void* data, size_t n);
// The CRC-32 of what `crc` was the CRC-32 of, followed by [data, data + n): crc32Of in parts.
uint32_t crc32Update(uint32_t crc, const void* data, size_t n);

// CRC-32C (Castagnoli's polynomial, as Zarr v3's crc32c codec appends to a shard's index).
uint32_t crc32cOf(const void* data, size_t n);

}  // namespace vdiso

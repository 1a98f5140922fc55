// CRC-32 (zlib's polynomial) of a byte range: the checksum of a store's header, index and
// bricks (io/store/store_format.h), and of the ranges a remote store's disk cache keeps
// (io/remote/disk_cache.h). A header of its own so that neither includes the other.
#pragma once

#include <cstddef>
#include <cstdint>

namespace vdiso {

uint32_t crc32Of(const void* data, size_t n);

}  // namespace vdiso

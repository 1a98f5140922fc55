// The checksums of io/crc32.h against their standard check values (the CRC catalogue's, of
// "123456789"), and crc32Update in parts against one call: stores written by any build verify
// in any other.
#include <gtest/gtest.h>

#include <cstring>
#include <random>
#include <vector>

#include "io/crc32.h"

namespace vdiso {
namespace {

TEST(Crc32, CheckValuesAndPartsAgree) {
    const char* check = "123456789";
    EXPECT_EQ(crc32Of(check, 9), 0xCBF43926u);   // CRC-32 (zlib, PNG, the store format)
    EXPECT_EQ(crc32cOf(check, 9), 0xE3069283u);  // CRC-32C (Zarr v3)
    EXPECT_EQ(crc32Of(check, 0), 0u);
    std::vector<unsigned char> bytes(100003);
    std::mt19937 rng(5);
    for (unsigned char& b : bytes) b = static_cast<unsigned char>(rng());
    const uint32_t whole = crc32Of(bytes.data(), bytes.size());
    for (size_t cut : {size_t(0), size_t(1), size_t(4095), size_t(65536), bytes.size()})
        EXPECT_EQ(crc32Update(crc32Of(bytes.data(), cut), bytes.data() + cut, bytes.size() - cut), whole) << cut;
}

}  // namespace
}  // namespace vdiso

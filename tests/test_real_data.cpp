// The real default dataset (Debian's mricron-data MRI heads, fetched by scripts/fetch_data.sh
// into $VDISO_DATA_DIR): converted through the store with every sample intact.
#include <gtest/gtest.h>

#include <cstdlib>

#include "io/store/brick_store.h"
#include "io/store/store_writer.h"
#include "io/readers/volume_open.h"
#include "tests/test_util.h"

namespace vdiso {
namespace {

TEST(RealData, MriHeadRoundTripsThroughTheStore) {
    for (const char* name : {"ch2.nii.gz", "ch2better.nii.gz"}) {
        const std::string path = test::dataFile(name);
        if (path.empty()) GTEST_SKIP() << "VDISO_DATA_DIR has no " << name << " (scripts/test.sh fetches it)";
        auto whole = openVolume(path, {});
        const std::vector<unsigned char> samples = test::readAllSamples(*whole, 7);
        EXPECT_EQ(whole->info().type, ScalarType::U8);

        test::ScratchDir dir;
        auto source = openVolume(path, {});
        writeBrickStore(*source, dir.file("mri.vdiso"), {});
        const BrickStoreReader store(dir.file("mri.vdiso"));
        EXPECT_EQ(store.volume().dims, whole->info().dims);
        EXPECT_EQ(test::compareStoreWithSamples(store, samples), "") << name;
    }
}

}  // namespace
}  // namespace vdiso

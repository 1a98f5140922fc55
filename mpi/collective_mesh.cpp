#include "mpi/collective_mesh.h"

#include <mpi.h>

#include <algorithm>
#include <climits>
#include <cstring>
#include <vector>

#include "io/error.h"
#include "io/mesh/mesh_writer.h"
#include "io/mesh/stl_writer.h"
#include "mpi/rank_status.h"
#include "mpi/shared_output.h"

namespace vdiso::mpi {

namespace {

// Bytes per collective write call: MPI counts are int.
constexpr size_t kWriteChunk = size_t(1) << 30;

std::string mpiErrorText(int code) {
    char text[MPI_MAX_ERROR_STRING];
    int length = 0;
    MPI_Error_string(code, text, &length);
    return std::string(text, size_t(length));
}

// Writes `bytes` at `offset` with every rank: as many collective calls on each rank as the
// largest region needs. A failure is kept (the first) and the remaining calls are still made
// with nothing to write, so that no rank is left waiting in one.
void writeAtAll(const Communicator& comm, MPI_File file, const std::vector<unsigned char>& bytes,
                uint64_t offset, std::string& error) {
    const uint64_t rounds = comm.max((bytes.size() + kWriteChunk - 1) / kWriteChunk);
    for (uint64_t k = 0; k < rounds; ++k) {
        const size_t begin = std::min(bytes.size(), size_t(k) * kWriteChunk);
        const size_t n = error.empty() ? std::min(kWriteChunk, bytes.size() - begin) : 0;
        MPI_Status status;
        const int code = MPI_File_write_at_all(file, MPI_Offset(offset + begin), bytes.data() + begin, int(n),
                                               MPI_BYTE, &status);
        if (code != MPI_SUCCESS && error.empty()) error = "write failed: " + mpiErrorText(code);
    }
}

// A region of the file this rank writes.
struct Region {
    std::vector<unsigned char> bytes;
    uint64_t offset;
};

// Opens the shared temporary file, writes every rank's `regions` (each rank as many, in order),
// syncs, closes and puts the file into place.
void writeRegionsCollectively(const Communicator& comm, const std::string& path, bool overwrite,
                              const std::vector<Region>& regions) {
    // Rank 0 names the temporary file; the others learn it. It goes unless committed.
    RankSharedOutput output(comm, path, overwrite);
    const std::string& temporary = output.temporary();

    MPI_File file = MPI_FILE_NULL;
    std::string error;
    const int openCode = MPI_File_open(MPI_Comm_f2c(MPI_Fint(comm.handle())), temporary.c_str(), MPI_MODE_CREATE | MPI_MODE_WRONLY,
                                       MPI_INFO_NULL, &file);
    if (openCode != MPI_SUCCESS) error = "cannot create " + temporary + ": " + mpiErrorText(openCode);
    try {
        agreeAllSucceeded(comm, !error.empty(), error);
    } catch (...) {
        if (file != MPI_FILE_NULL) MPI_File_close(&file);
        throw;
    }

    for (const Region& region : regions) writeAtAll(comm, file, region.bytes, region.offset, error);
    if (int code = MPI_File_sync(file); code != MPI_SUCCESS && error.empty()) error = "sync failed: " + mpiErrorText(code);
    if (int code = MPI_File_close(&file); code != MPI_SUCCESS && error.empty())
        error = "close failed: " + mpiErrorText(code);
    if (!error.empty()) error = temporary + ": " + error;
    agreeAllSucceeded(comm, !error.empty(), error);
    output.commit();  // into place: without overwrite, link() refuses a file that appeared meanwhile
}

}  // namespace

void writePlyCollectively(const Communicator& comm, const std::string& path, bool overwrite,
                          const TriangleMesh& part, const RankMeshNumbering& numbering) {
    std::vector<unsigned char> header;
    if (comm.rank() == 0) {
        const std::string text = plyMeshHeader(numbering.totalVertices, numbering.totalTriangles);
        header.assign(text.begin(), text.end());
    }
    writeRegionsCollectively(
        comm, path, overwrite,
        {{std::move(header), 0},
         {plyVertexRecords(part), kPlyHeaderBytes + numbering.firstVertex * kPlyVertexBytes},
         {plyFaceRecords(part),
          kPlyHeaderBytes + numbering.totalVertices * kPlyVertexBytes + numbering.firstTriangle * kPlyFaceBytes}});
}

void writeStlCollectively(const Communicator& comm, const std::string& path, bool overwrite,
                          const TriangleMesh& part) {
    const uint64_t first = comm.exclusiveSum(part.triangleCount()), total = comm.sum(part.triangleCount());
    // The same on every rank: refused alike, before any file is made.
    if (total > UINT32_MAX)
        throw RankFailure(0, 1, path + ": " + std::to_string(total) + " triangles, too many for STL's 32-bit count");
    std::vector<unsigned char> header;
    if (comm.rank() == 0) {
        const auto bytes = stlHeader(uint32_t(total));
        header.assign(bytes.begin(), bytes.end());
    }
    writeRegionsCollectively(comm, path, overwrite,
                             {{std::move(header), 0}, {stlTriangleRecords(part), kStlHeaderBytes + first * kStlTriangleBytes}});
}

}  // namespace vdiso::mpi

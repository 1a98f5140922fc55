#include "mpi/collective_ply.h"

#include <mpi.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <climits>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <vector>

#include "io/error.h"
#include "io/mesh_writer.h"
#include "mpi/rank_status.h"

namespace vdiso::mpi {

namespace {

// Bytes per collective write call: MPI counts are int.
constexpr size_t kWriteChunk = size_t(1) << 30;

int exitCodeOne(const std::exception&) { return 1; }

std::string mpiErrorText(int code) {
    char text[MPI_MAX_ERROR_STRING];
    int length = 0;
    MPI_Error_string(code, text, &length);
    return std::string(text, size_t(length));
}

std::vector<unsigned char> vertexRecords(const TriangleMesh& part) {
    std::vector<unsigned char> bytes(part.positions.size() * kPlyVertexBytes);
    for (size_t i = 0; i < part.positions.size(); ++i) {
        const float v[6] = {part.positions[i].x, part.positions[i].y, part.positions[i].z,
                            part.normals[i].x,   part.normals[i].y,   part.normals[i].z};
        std::memcpy(bytes.data() + i * kPlyVertexBytes, v, kPlyVertexBytes);
    }
    return bytes;
}

std::vector<unsigned char> faceRecords(const TriangleMesh& part) {
    std::vector<unsigned char> bytes(part.triangleCount() * kPlyFaceBytes);
    for (size_t t = 0; t < part.triangleCount(); ++t) {
        bytes[t * kPlyFaceBytes] = 3;
        std::memcpy(bytes.data() + t * kPlyFaceBytes + 1, &part.indices[3 * t], 12);
    }
    return bytes;
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

}  // namespace

void writePlyCollectively(const Communicator& comm, const std::string& path, bool overwrite,
                          const TriangleMesh& part, const RankMeshNumbering& numbering) {
    // Rank 0 names the temporary file; the others learn it.
    std::string temporary;
    runPhase(comm, [&] {
        if (comm.rank() != 0) return;
        if (!overwrite && std::filesystem::exists(path))
            throwIoError(path, "already exists (pass --force to replace it)");
        temporary = path + ".partial.mpi." + std::to_string(::getpid());
    }, exitCodeOne);
    temporary = comm.broadcast(temporary, 0);
    auto removeTemporary = [&] {
        if (comm.rank() == 0) std::remove(temporary.c_str());
    };

    MPI_File file = MPI_FILE_NULL;
    std::string error;
    const int openCode = MPI_File_open(MPI_COMM_WORLD, temporary.c_str(), MPI_MODE_CREATE | MPI_MODE_WRONLY,
                                       MPI_INFO_NULL, &file);
    if (openCode != MPI_SUCCESS) error = "cannot create " + temporary + ": " + mpiErrorText(openCode);
    try {
        agreeAllSucceeded(comm, !error.empty(), error);
    } catch (...) {
        if (file != MPI_FILE_NULL) MPI_File_close(&file);
        removeTemporary();
        throw;
    }

    // MPI_File_set_size truncates a file left by an earlier run under the same name.
    if (int code = MPI_File_set_size(file, 0); code != MPI_SUCCESS) error = "truncate failed: " + mpiErrorText(code);
    const std::vector<unsigned char> header = [&] {
        if (comm.rank() != 0) return std::vector<unsigned char>();
        const std::string text = plyMeshHeader(numbering.totalVertices, numbering.totalTriangles);
        return std::vector<unsigned char>(text.begin(), text.end());
    }();
    writeAtAll(comm, file, header, 0, error);
    writeAtAll(comm, file, vertexRecords(part), kPlyHeaderBytes + numbering.firstVertex * kPlyVertexBytes, error);
    writeAtAll(comm, file, faceRecords(part),
               kPlyHeaderBytes + numbering.totalVertices * kPlyVertexBytes + numbering.firstTriangle * kPlyFaceBytes,
               error);
    if (int code = MPI_File_sync(file); code != MPI_SUCCESS && error.empty()) error = "sync failed: " + mpiErrorText(code);
    if (int code = MPI_File_close(&file); code != MPI_SUCCESS && error.empty())
        error = "close failed: " + mpiErrorText(code);
    try {
        if (!error.empty()) error = temporary + ": " + error;
        agreeAllSucceeded(comm, !error.empty(), error);
        // Into place: without overwrite, link() refuses a file that appeared meanwhile.
        runPhase(comm, [&] {
            if (comm.rank() != 0) return;
            if (overwrite) {
                if (std::rename(temporary.c_str(), path.c_str()) != 0)
                    throwIoError(path, std::string("cannot rename into place: ") + std::strerror(errno));
            } else {
                if (::link(temporary.c_str(), path.c_str()) != 0)
                    throwIoError(path, errno == EEXIST ? std::string("already exists (pass --force to replace it)")
                                                       : std::string("cannot link into place: ") + std::strerror(errno));
                ::unlink(temporary.c_str());
            }
        }, exitCodeOne);
    } catch (...) {
        removeTemporary();
        throw;
    }
}

}  // namespace vdiso::mpi

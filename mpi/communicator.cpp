#include "mpi/communicator.h"

#include <mpi.h>

#include <algorithm>
#include <climits>

namespace vdiso::mpi {

namespace {

void check(int code, const char* call) {
    if (code == MPI_SUCCESS) return;
    char text[MPI_MAX_ERROR_STRING];
    int length = 0;
    MPI_Error_string(code, text, &length);
    throw MpiError(std::string(call) + " failed: " + std::string(text, size_t(length)));
}

// MPI counts are int: larger messages are refused rather than truncated.
int countOf(size_t n, const char* call) {
    if (n > size_t(INT_MAX)) throw MpiError(std::string(call) + ": message of " + std::to_string(n) + " items is too large");
    return int(n);
}

}  // namespace

MpiSession::MpiSession(int& argc, char**& argv) {
    int provided = 0;
    check(MPI_Init_thread(&argc, &argv, MPI_THREAD_FUNNELED, &provided), "MPI_Init_thread");
    // Errors come back as codes, which check() turns into exceptions: a rank that fails then
    // reaches the collective status check instead of aborting the job mid-write.
    MPI_Comm_set_errhandler(MPI_COMM_WORLD, MPI_ERRORS_RETURN);
    MPI_File_set_errhandler(MPI_FILE_NULL, MPI_ERRORS_RETURN);
}

MpiSession::~MpiSession() { MPI_Finalize(); }

Communicator::Communicator() : Communicator(int(MPI_Comm_c2f(MPI_COMM_WORLD))) {}

Communicator::Communicator(int handle) : mHandle(handle) {
    MPI_Comm_rank(MPI_Comm_f2c(MPI_Fint(mHandle)), &mRank);
    MPI_Comm_size(MPI_Comm_f2c(MPI_Fint(mHandle)), &mSize);
}

// Kept until MPI_Finalize, which frees it: a job makes one or two.
Communicator Communicator::reversed() const {
    MPI_Comm comm = MPI_COMM_NULL;
    check(MPI_Comm_split(MPI_Comm_f2c(MPI_Fint(mHandle)), 0, mSize - 1 - mRank, &comm), "MPI_Comm_split");
    MPI_Comm_set_errhandler(comm, MPI_ERRORS_RETURN);
    return Communicator(int(MPI_Comm_c2f(comm)));
}

std::vector<uint64_t> Communicator::exclusiveOr(std::span<const uint64_t> bits) const {
    std::vector<uint64_t> result(bits.size(), 0);
    check(MPI_Exscan(bits.data(), result.data(), countOf(bits.size(), "MPI_Exscan"), MPI_UINT64_T, MPI_BOR,
                     MPI_Comm_f2c(MPI_Fint(mHandle))),
          "MPI_Exscan");
    if (mRank == 0) std::fill(result.begin(), result.end(), 0);  // rank 0's result is undefined
    return result;
}

void Communicator::gatherBytes(std::span<const unsigned char> bytes, int root, std::span<unsigned char> into) const {
    const MPI_Comm comm = MPI_Comm_f2c(MPI_Fint(mHandle));
    const int count = countOf(bytes.size(), "MPI_Gatherv");
    std::vector<int> counts(mRank == root ? size_t(mSize) : 0), offsets(counts.size());
    check(MPI_Gather(&count, 1, MPI_INT, counts.data(), 1, MPI_INT, root, comm), "MPI_Gather");
    for (size_t r = 1; r < counts.size(); ++r) offsets[r] = offsets[r - 1] + counts[r - 1];
    check(MPI_Gatherv(bytes.data(), count, MPI_BYTE, into.data(), counts.data(), offsets.data(), MPI_BYTE, root, comm),
          "MPI_Gatherv");
}

uint64_t Communicator::exclusiveSum(uint64_t value) const {
    uint64_t result = 0;
    check(MPI_Exscan(&value, &result, 1, MPI_UINT64_T, MPI_SUM, MPI_Comm_f2c(MPI_Fint(mHandle))), "MPI_Exscan");
    return mRank == 0 ? 0 : result;  // rank 0's result is undefined
}

uint64_t Communicator::sum(uint64_t value) const {
    uint64_t result = 0;
    check(MPI_Allreduce(&value, &result, 1, MPI_UINT64_T, MPI_SUM, MPI_Comm_f2c(MPI_Fint(mHandle))), "MPI_Allreduce");
    return result;
}

int Communicator::min(int value) const {
    int result = 0;
    check(MPI_Allreduce(&value, &result, 1, MPI_INT, MPI_MIN, MPI_Comm_f2c(MPI_Fint(mHandle))), "MPI_Allreduce");
    return result;
}

uint64_t Communicator::max(uint64_t value) const {
    uint64_t result = 0;
    check(MPI_Allreduce(&value, &result, 1, MPI_UINT64_T, MPI_MAX, MPI_Comm_f2c(MPI_Fint(mHandle))), "MPI_Allreduce");
    return result;
}

std::vector<uint64_t> Communicator::gather(uint64_t value, int root) const {
    std::vector<uint64_t> all(mRank == root ? size_t(mSize) : 0);
    check(MPI_Gather(&value, 1, MPI_UINT64_T, all.data(), 1, MPI_UINT64_T, root, MPI_Comm_f2c(MPI_Fint(mHandle))), "MPI_Gather");
    return all;
}

std::vector<double> Communicator::gather(double value, int root) const {
    std::vector<double> all(mRank == root ? size_t(mSize) : 0);
    check(MPI_Gather(&value, 1, MPI_DOUBLE, all.data(), 1, MPI_DOUBLE, root, MPI_Comm_f2c(MPI_Fint(mHandle))), "MPI_Gather");
    return all;
}

int Communicator::broadcast(int value, int root) const {
    check(MPI_Bcast(&value, 1, MPI_INT, root, MPI_Comm_f2c(MPI_Fint(mHandle))), "MPI_Bcast");
    return value;
}

std::string Communicator::broadcast(const std::string& value, int root) const {
    const int length = broadcast(countOf(value.size(), "MPI_Bcast"), root);
    std::string result = mRank == root ? value : std::string(size_t(length), '\0');
    check(MPI_Bcast(result.data(), length, MPI_CHAR, root, MPI_Comm_f2c(MPI_Fint(mHandle))), "MPI_Bcast");
    return result;
}

std::vector<std::vector<uint64_t>> Communicator::exchange(const std::vector<std::vector<uint64_t>>& send) const {
    if (send.size() != size_t(mSize)) throw std::invalid_argument("Communicator::exchange: one list per rank");
    const size_t ranks = size_t(mSize);
    std::vector<int> sendCounts(ranks), sendOffsets(ranks), receiveCounts(ranks), receiveOffsets(ranks);
    std::vector<uint64_t> sendBuffer;
    for (int r = 0; r < mSize; ++r) {
        sendOffsets[size_t(r)] = countOf(sendBuffer.size(), "MPI_Alltoallv");
        sendCounts[size_t(r)] = countOf(send[size_t(r)].size(), "MPI_Alltoallv");
        sendBuffer.insert(sendBuffer.end(), send[size_t(r)].begin(), send[size_t(r)].end());
    }
    countOf(sendBuffer.size(), "MPI_Alltoallv");
    check(MPI_Alltoall(sendCounts.data(), 1, MPI_INT, receiveCounts.data(), 1, MPI_INT, MPI_Comm_f2c(MPI_Fint(mHandle))),
          "MPI_Alltoall");
    size_t total = 0;
    for (int r = 0; r < mSize; ++r) {
        receiveOffsets[size_t(r)] = countOf(total, "MPI_Alltoallv");
        total += size_t(receiveCounts[size_t(r)]);
    }
    countOf(total, "MPI_Alltoallv");
    std::vector<uint64_t> receiveBuffer(total);
    check(MPI_Alltoallv(sendBuffer.data(), sendCounts.data(), sendOffsets.data(), MPI_UINT64_T,
                        receiveBuffer.data(), receiveCounts.data(), receiveOffsets.data(), MPI_UINT64_T,
                        MPI_Comm_f2c(MPI_Fint(mHandle))),
          "MPI_Alltoallv");
    std::vector<std::vector<uint64_t>> received(ranks);
    for (int r = 0; r < mSize; ++r) {
        const auto first = receiveBuffer.begin() + receiveOffsets[size_t(r)];
        received[size_t(r)].assign(first, first + receiveCounts[size_t(r)]);
    }
    return received;
}

void Communicator::barrier() const { check(MPI_Barrier(MPI_Comm_f2c(MPI_Fint(mHandle))), "MPI_Barrier"); }

std::vector<uint64_t> Communicator::allgather(uint64_t value) const {
    std::vector<uint64_t> all(static_cast<size_t>(mSize));
    check(MPI_Allgather(&value, 1, MPI_UINT64_T, all.data(), 1, MPI_UINT64_T, MPI_Comm_f2c(MPI_Fint(mHandle))),
          "MPI_Allgather");
    return all;
}

void Communicator::sumInto(std::vector<uint64_t>& values, int root) const {
    const MPI_Comm comm = MPI_Comm_f2c(MPI_Fint(mHandle));
    const int n = countOf(values.size(), "MPI_Reduce");
    if (mRank == root)
        check(MPI_Reduce(MPI_IN_PLACE, values.data(), n, MPI_UINT64_T, MPI_SUM, root, comm), "MPI_Reduce");
    else
        check(MPI_Reduce(values.data(), nullptr, n, MPI_UINT64_T, MPI_SUM, root, comm), "MPI_Reduce");
}

void Communicator::transfer(const std::vector<Send>& sends, const std::vector<Receive>& receives) const {
    constexpr uint64_t kPiece = uint64_t(1) << 30;
    constexpr int kTag = 7;
    const MPI_Comm comm = MPI_Comm_f2c(MPI_Fint(mHandle));
    std::vector<MPI_Request> requests;
    // Posted before anything is waited on, so that no pair of ranks waits on the other.
    for (const Receive& r : receives)
        for (uint64_t at = 0; at < r.size; at += kPiece) {
            requests.emplace_back();
            check(MPI_Irecv(static_cast<char*>(r.bytes) + at, int(std::min(kPiece, r.size - at)), MPI_BYTE, r.rank,
                            kTag, comm, &requests.back()),
                  "MPI_Irecv");
        }
    for (const Send& s : sends)
        for (uint64_t at = 0; at < s.size; at += kPiece) {
            requests.emplace_back();
            check(MPI_Isend(static_cast<const char*>(s.bytes) + at, int(std::min(kPiece, s.size - at)), MPI_BYTE,
                            s.rank, kTag, comm, &requests.back()),
                  "MPI_Isend");
        }
    check(MPI_Waitall(int(requests.size()), requests.data(), MPI_STATUSES_IGNORE), "MPI_Waitall");
}

}  // namespace vdiso::mpi

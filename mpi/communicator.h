// The processes of an mpirun job as the rest of vdiso_mpi sees them: MPI_COMM_WORLD behind a
// few collective operations on our own types, so that <mpi.h> stays in communicator.cpp.
//
// Every member function but rank() and size() is collective: all ranks call it, in the same
// order, or the job hangs. The MPI error handler is MPI_ERRORS_RETURN; a failed call throws
// MpiError naming it (the caller's phase check then ends the job cleanly). Not thread-safe:
// one thread per rank makes the calls (MPI_THREAD_FUNNELED).
#pragma once

#include <cstdint>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

namespace vdiso::mpi {

class MpiError : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};

// Starts MPI (MPI_Init_thread) for the life of the object and ends it (MPI_Finalize).
// One per process, made first in main().
class MpiSession {
public:
    MpiSession(int& argc, char**& argv);
    ~MpiSession();
    MpiSession(const MpiSession&) = delete;
    MpiSession& operator=(const MpiSession&) = delete;
};

class Communicator {
public:
    Communicator();  // the world: every rank of the job
    int rank() const { return mRank; }
    int size() const { return mSize; }

    // The communicator as a Fortran handle, for the MPI calls made outside communicator.cpp
    // (MPI-IO): MPI_Comm_f2c(handle()).
    int handle() const { return mHandle; }

    // The same ranks in the opposite order (rank r here is rank size() - 1 - r there).
    Communicator reversed() const;

    // The sum of `value` over the ranks before this one (0 on rank 0): MPI_Exscan.
    uint64_t exclusiveSum(uint64_t value) const;
    uint64_t sum(uint64_t value) const;
    int min(int value) const;
    uint64_t max(uint64_t value) const;
    // The bitwise OR of `bits` over the ranks before this one (zeros on rank 0): MPI_Exscan.
    // Every rank gives as many words.
    std::vector<uint64_t> exclusiveOr(std::span<const uint64_t> bits) const;
    // `values` from every rank, rank by rank, on rank `root` (empty elsewhere).
    std::vector<uint64_t> gather(uint64_t value, int root) const;
    std::vector<double> gather(double value, int root) const;
    // Every rank's bytes, one after another in rank order, into `into` on `root` (unused
    // elsewhere). The caller sizes `into` to the ranks' total (sum()) before, so that nothing can
    // fail on one rank between the collective calls; at most 2 GiB in all (MPI counts are int).
    void gatherBytes(std::span<const unsigned char> bytes, int root, std::span<unsigned char> into) const;
    // `root`'s value on every rank.
    int broadcast(int value, int root) const;
    std::string broadcast(const std::string& value, int root) const;
    // Sends send[r] to rank r and returns what each rank sent to this one (MPI_Alltoallv).
    // `send` has size() lists.
    std::vector<std::vector<uint64_t>> exchange(const std::vector<std::vector<uint64_t>>& send) const;
    void barrier() const;

    // Every rank's `value`, rank by rank, on every rank (MPI_Allgather).
    std::vector<uint64_t> allgather(uint64_t value) const;
    // Adds every rank's `values` element by element into `root`'s (MPI_Reduce); the others'
    // are left as they were. The same size on every rank.
    void sumInto(std::vector<uint64_t>& values, int root) const;

    // Byte regions sent to and received from other ranks, point to point (MPI_Isend,
    // MPI_Irecv), returning when all are done. Not collective: every send must meet its
    // receive on the other rank (the same pair, in the same order, the same size), or both wait
    // forever. Regions may exceed MPI's int counts: they go in pieces of 1 GiB.
    struct Send {
        int rank;
        const void* bytes;
        uint64_t size;
    };
    struct Receive {
        int rank;
        void* bytes;
        uint64_t size;
    };
    void transfer(const std::vector<Send>& sends, const std::vector<Receive>& receives) const;

private:
    explicit Communicator(int handle);
    int mHandle;  // the MPI communicator as a Fortran handle (MPI_Comm_c2f), so <mpi.h> stays out
    int mRank = 0, mSize = 1;
};

}  // namespace vdiso::mpi

// One binary PLY written by all ranks at once (MPI-IO), in the layout of io/mesh_writer.h, so
// the file is the one `vdiso extract -o MESH.ply` writes, byte for byte.
//
// Rank 0 refuses an existing output (without `overwrite`) and names a temporary file beside
// it (OUTPUT.partial.mpi.<pid>, shared_output.h); all ranks open it (MPI_File_open) and write their records at
// the offsets the welded numbering gives (MPI_File_write_at_all: rank r's vertex records at
// header + firstVertex * 24, its faces after all vertices at firstTriangle * 13), rank 0 the
// header with the totals. Only when every rank has written, synced and closed it does rank 0
// link it into place (a rename with `overwrite`); on any failure the temporary file is removed
// and the output does not appear. Each step ends in a collective status check (rank_status.h).
#pragma once

#include <string>

#include "core/mesh.h"
#include "mpi/communicator.h"
#include "mpi/rank_weld.h"

namespace vdiso::mpi {

// Collective. `part`: this rank's owned vertices and its triangles in global numbers (as
// weldAcrossRanks leaves them, mapped to the output space already). Throws RankFailure on
// every rank when any rank failed.
void writePlyCollectively(const Communicator& comm, const std::string& path, bool overwrite,
                          const TriangleMesh& part, const RankMeshNumbering& numbering);

}  // namespace vdiso::mpi

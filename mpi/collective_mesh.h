// One mesh file written by all ranks at once (MPI-IO), in the layouts of io/mesh/mesh_writer.h (PLY)
// and io/mesh/stl_writer.h (STL), so the file is the one `vdiso extract -o MESH` writes, byte for
// byte.
//
// The file is shared by the ranks (mpi/shared_output.h): written under a temporary name beside
// the output (OUTPUT.partial.mpi.<pid>) and linked into place only when every rank has
// written, synced and closed it. Each rank writes its records at the offsets the ranks before
// it give (MPI_File_write_at_all), rank 0 the header with the totals. Each step ends in a
// collective status check (rank_status.h): on any failure the temporary file is removed and
// the output does not appear.
#pragma once

#include <string>

#include "core/mesh.h"
#include "mpi/communicator.h"
#include "mpi/rank_weld.h"

namespace vdiso::mpi {

// Collective. PLY: `part` holds this rank's owned vertices and its triangles in global numbers
// (as weldAcrossRanks leaves them, mapped to the output space already); rank r's vertex records
// at header + firstVertex * 24, its faces after all vertices at firstTriangle * 13. Throws
// RankFailure on every rank when any rank failed.
void writePlyCollectively(const Communicator& comm, const std::string& path, bool overwrite,
                          const TriangleMesh& part, const RankMeshNumbering& numbering);

// Collective. STL: `part` holds this rank's triangles over its own vertices (STL shares none, so
// no welding), in the output space; they follow the triangles of the ranks before it. Throws
// RankFailure on every rank when any rank failed, or when the ranks' triangles together are more
// than STL's u32 count.
void writeStlCollectively(const Communicator& comm, const std::string& path, bool overwrite,
                          const TriangleMesh& part);

}  // namespace vdiso::mpi

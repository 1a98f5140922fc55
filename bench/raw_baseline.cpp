// What a user does without vdiso: read the raw volume whole from cold disk, then run VTK's
// Flying Edges on it. The baseline of the out-of-core issue's I/O tables ("the time a user
// would spend instead").
//
//   vdiso_raw_baseline RAW --dims X,Y,Z --type u8|i16|u16|f32 --iso V [--threads N]
//
// Drops the file's pages first (posix_fadvise DONTNEED), reads it with large sequential
// reads into a vtkImageData, runs vtkFlyingEdges3D (normals on, as vdiso) on N threads, and
// prints one JSON line: read_s, flying_edges_s, total_s, triangles, bytes. The read alone is
// reported on stderr as soon as it is done, for volumes where Flying Edges then runs out of
// memory (it needs a byte of scratch per voxel besides the volume).
#include <chrono>
#include <cstdio>
#include <algorithm>
#include <cstdlib>
#include <optional>
#include <string>

#include <fcntl.h>
#include <unistd.h>

// vtkSMPTools.h does not compile as C++20 in VTK 9.1; its Initialize forwards to this API.
#include <SMP/Common/vtkSMPToolsAPI.h>
#include <vtkFlyingEdges3D.h>
#include <vtkImageData.h>
#include <vtkNew.h>
#include <vtkPolyData.h>
#include <vtkType.h>

#include "core/scalar_type.h"

namespace {

[[noreturn]] void usage(const char* why) {
    std::fprintf(stderr, "vdiso_raw_baseline: %s\nusage: vdiso_raw_baseline RAW --dims X,Y,Z "
                         "--type u8|i16|u16|f32 --iso V [--threads N]\n", why);
    std::exit(2);
}

int vtkTypeOf(vdiso::ScalarType t) {
    switch (t) {
        case vdiso::ScalarType::U8: return VTK_UNSIGNED_CHAR;
        case vdiso::ScalarType::I16: return VTK_SHORT;
        case vdiso::ScalarType::U16: return VTK_UNSIGNED_SHORT;
        case vdiso::ScalarType::F32: break;
    }
    return VTK_FLOAT;
}

double secondsSince(std::chrono::steady_clock::time_point start) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace

int main(int argc, char** argv) {
    if (argc < 2) usage("expects RAW");
    const std::string path = argv[1];
    long dims[3] = {0, 0, 0};
    std::optional<vdiso::ScalarType> type;
    double iso = 0;
    bool isoGiven = false;
    int threads = 1;
    for (int i = 2; i < argc; ++i) {
        const std::string a = argv[i];
        if (i + 1 >= argc) usage(("missing value after " + a).c_str());
        const std::string v = argv[++i];
        if (a == "--dims") {
            if (std::sscanf(v.c_str(), "%ld,%ld,%ld", &dims[0], &dims[1], &dims[2]) != 3) usage("bad --dims");
        } else if (a == "--type") {
            type = vdiso::parseScalarType(v);
            if (!type) usage("bad --type");
        } else if (a == "--iso") {
            iso = std::atof(v.c_str());
            isoGiven = true;
        } else if (a == "--threads") {
            threads = std::atoi(v.c_str());
        } else {
            usage(("unknown option " + a).c_str());
        }
    }
    if (!type || !isoGiven || dims[0] < 2) usage("needs --dims, --type and --iso");

    const int fd = ::open(path.c_str(), O_RDONLY);
    if (fd < 0) usage(("cannot open " + path).c_str());
    ::posix_fadvise(fd, 0, 0, POSIX_FADV_DONTNEED);  // cold: the file's pages leave the cache

    const auto start = std::chrono::steady_clock::now();
    vtkNew<vtkImageData> image;
    image->SetDimensions(int(dims[0]), int(dims[1]), int(dims[2]));
    image->AllocateScalars(vtkTypeOf(*type), 1);
    auto* dst = static_cast<char*>(image->GetScalarPointer());
    const size_t bytes = size_t(dims[0]) * size_t(dims[1]) * size_t(dims[2]) * vdiso::scalarSize(*type);
    for (size_t done = 0; done < bytes;) {
        const ssize_t r = ::pread(fd, dst + done, std::min<size_t>(bytes - done, 64u << 20), off_t(done));
        if (r <= 0) usage(("short read of " + path).c_str());
        done += size_t(r);
    }
    ::close(fd);
    const double readSeconds = secondsSince(start);
    // Said at once: Flying Edges may not get to finish (its scratch is a byte per voxel).
    std::fprintf(stderr, "{\"file\": \"%s\", \"bytes\": %zu, \"read_s\": %.4f}\n", path.c_str(), bytes,
                 readSeconds);

    vtk::detail::smp::vtkSMPToolsAPI::GetInstance().Initialize(threads);
    const auto feStart = std::chrono::steady_clock::now();
    vtkNew<vtkFlyingEdges3D> fe;
    fe->SetInputData(image);
    fe->SetValue(0, iso);
    fe->ComputeNormalsOn();
    fe->ComputeGradientsOff();
    fe->ComputeScalarsOff();
    fe->Update();
    const double feSeconds = secondsSince(feStart);
    std::printf("{\"file\": \"%s\", \"iso\": %g, \"threads\": %d, \"bytes\": %zu, \"read_s\": %.4f, "
                "\"flying_edges_s\": %.4f, \"total_s\": %.4f, \"triangles\": %lld}\n",
                path.c_str(), iso, threads, bytes, readSeconds, feSeconds, secondsSince(start),
                (long long)fe->GetOutput()->GetNumberOfPolys());
    return 0;
}

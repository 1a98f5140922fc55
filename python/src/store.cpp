// Stores from Python: _Store (what a store is), _Session (app/extract_session.h: one brick cache
// across the frames it extracts) and Mesh (NumPy arrays over the C++ mesh, without a copy).
#include <pybind11/numpy.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <array>
#include <cstring>
#include <filesystem>
#include <memory>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <string_view>

#include "app/extract_session.h"
#include "app/store_info.h"
#include "app/view_camera.h"
#include "arrays.h"
#include "bindings.h"
#include "core/view_presets.h"
#include "io/error.h"
#include "io/mesh/mesh_writer.h"
#include "io/render/renderer.h"
#include "released.h"

namespace vdiso::py {

namespace pyb = pybind11;
using namespace pybind11::literals;

namespace {

struct Mesh {
    TriangleMesh mesh;
    PointSet points;
    pyb::dict stats;
};

pyb::object meshArray(pyb::object self, int which) {
    Mesh& m = self.cast<Mesh&>();
    switch (which) {
        case 0: return arrayOver(rowsOrEmpty(&m.mesh.positions.data()->x), m.mesh.positions.size(), 3, self);
        case 1: return arrayOver(rowsOrEmpty(&m.mesh.normals.data()->x), m.mesh.normals.size(), 3, self);
        case 2: return arrayOver(rowsOrEmpty(m.mesh.indices.data()), m.mesh.triangleCount(), 3, self);
        case 3: return arrayOver(rowsOrEmpty(&m.points.positions.data()->x), m.points.size(), 3, self);
    }
    return arrayOver(rowsOrEmpty(&m.points.normals.data()->x), m.points.size(), 3, self);
}

struct Store {
    std::shared_ptr<BrickStoreReader> reader;
};

RemoteOptions remoteOptions(const std::string& s3Endpoint, bool anonymous, const std::string& diskCache) {
    RemoteOptions r;
    r.s3Endpoint = s3Endpoint;
    r.anonymous = anonymous;
    r.diskCacheDir = diskCache;
    return r;
}

class Session {
public:
    Session(const Store& store, ExtractSettings settings) : mStore(store.reader), mSession(*mStore, std::move(settings)) {}

    // Other settings for the frames to come; the cache and the tree stay (ExtractSession::reconfigure).
    void configure(ExtractSettings settings) {
        std::lock_guard lock(mFrameLock);
        mSession.reconfigure(std::move(settings));
    }

    // The camera of a frame: the one given (checked when it was made: cameraOf), its clip
    // planes fitted to the volume, else a named view (the default "normal").
    Camera camera(const std::optional<Camera>& given, const std::string& view, int width, int height) const {
        Camera c;
        if (given) {
            c = *given;
            fitClipPlanes(c, mStore->volume());
        } else {
            ViewChoice choice;
            try {
                choice = parseViewChoice(view);
            } catch (const std::invalid_argument& e) {
                throw SettingsError("view", e.what());
            }
            c = viewCamera(choice, mStore->volume(), width, height);
        }
        return c;
    }

    std::shared_ptr<Mesh> extract(const std::optional<Camera>& given, const std::string& view, int width, int height,
                                  pyb::object progress) {
        auto result = std::make_shared<Mesh>();
        std::string statsText;
        const Camera c = camera(given, view, width, height);
        runReleased([&](const ProgressFn& fraction) {
            // One frame at a time per session: Python threads may share one (frames()).
            std::lock_guard lock(mFrameLock);
            FrameOutput output;
            // Post-processing's side files are unnamed (io/mesh/mesh_output.h) in this folder.
            output.postBeside = (std::filesystem::temp_directory_path() / "vdiso-python.ply").string();
            ExtractFrame frame = mSession.extract(c, output, fraction);
            statsText = mSession.frameStats(frame, false).str();
            const SpaceTransform toWorld = mSession.meshTransform();
            transformMesh(toWorld, frame.mesh);
            transformPoints(toWorld, frame.points);
            result->mesh = std::move(frame.mesh);
            result->points = std::move(frame.points);
        }, progress);
        result->stats = pyb::module_::import("json").attr("loads")(statsText);
        return result;
    }

    // The frame drawn as the command line draws it (OSMesa): an (height, width, 3) uint8 image.
    pyb::array_t<uint8_t> render(const std::optional<Camera>& given, const std::string& view, int width, int height) {
        const Camera c = camera(given, view, width, height);
        RenderResult drawn;
        runReleased([&](const ProgressFn& fraction) {
            std::lock_guard lock(mFrameLock);
            const ExtractFrame frame = mSession.extract(c, {}, fraction);
            drawn = renderSurface(frame.mesh, frame.points, c);
        });
        // The camera's size is the picture's (the package refuses a camera of another).
        pyb::array_t<uint8_t> image({size_t(c.height), size_t(c.width), size_t(3)});
        uint8_t* out = image.mutable_data();
        for (size_t p = 0; p < size_t(c.width) * size_t(c.height); ++p)
            for (int k = 0; k < 3; ++k) out[3 * p + size_t(k)] = drawn.image.rgba[4 * p + size_t(k)];
        return image;
    }

private:
    std::shared_ptr<BrickStoreReader> mStore;
    ExtractSession mSession;
    std::mutex mFrameLock;
};

// Python's None: the library's default (ExtractSettings).
ExtractSettings settingsOf(const std::string& method, double iso, std::optional<double> lodError, int64_t threads,
                           std::optional<int64_t> cacheMb, bool largest, int64_t minPiece, int64_t smooth,
                           double decimate, bool volumeSpace) {
    ExtractSettings s;
    s.method = method;
    s.iso = iso;
    if (lodError) {
        s.lodError = *lodError;
        s.lodErrorGiven = true;
    }
    s.threads = int(checkedInt("threads", threads, 0, 256));  // 0: every core
    if (cacheMb) s.cacheMb = uint64_t(checkedInt("cache_mb", *cacheMb, 1, int64_t(1) << 30));
    s.post.largestPiece = largest;
    s.post.minPieceTriangles = uint64_t(checkedInt("min_piece", minPiece, 0, int64_t(1) << 40));
    s.post.smoothIterations = int(checkedInt("smooth", smooth, 0, 1000));
    s.post.decimateRatio = decimate;
    if (volumeSpace) s.physicalMeshes = false;
    return s;
}

pyb::tuple vec(const glm::dvec3& v) { return pyb::make_tuple(v.x, v.y, v.z); }

// A Mesh as pickle keeps it: its arrays' bytes and its stats.
template <class Array>
pyb::bytes bytesOf(const Array& a) {
    return pyb::bytes(reinterpret_cast<const char*>(a.data()), a.size() * sizeof(a[0]));
}

pyb::tuple meshState(const Mesh& m) {
    return pyb::make_tuple(bytesOf(m.mesh.positions), bytesOf(m.mesh.normals), bytesOf(m.mesh.indices),
                           bytesOf(m.points.positions), bytesOf(m.points.normals), m.stats);
}

template <class Array>
void fill(Array& a, const pyb::bytes& b, const char* what) {
    const std::string_view v = b;
    if (v.size() % sizeof(a[0]) != 0) throw std::invalid_argument(std::string("Mesh state: ") + what + " of a partial item");
    a.resize(v.size() / sizeof(a[0]));
    if (!v.empty()) std::memcpy(a.data(), v.data(), v.size());
}

std::shared_ptr<Mesh> meshFromState(const pyb::tuple& state) {
    if (state.size() != 6) throw std::invalid_argument("Mesh state: expects 6 items, not " + std::to_string(state.size()));
    auto m = std::make_shared<Mesh>();
    fill(m->mesh.positions, state[0].cast<pyb::bytes>(), "vertices");
    fill(m->mesh.normals, state[1].cast<pyb::bytes>(), "normals");
    fill(m->mesh.indices, state[2].cast<pyb::bytes>(), "faces");
    fill(m->points.positions, state[3].cast<pyb::bytes>(), "points");
    fill(m->points.normals, state[4].cast<pyb::bytes>(), "point normals");
    m->stats = state[5].cast<pyb::dict>();
    const size_t n = m->mesh.positions.size();
    bool fits = m->mesh.normals.size() == n && m->mesh.indices.size() % 3 == 0 &&
                m->points.normals.size() == m->points.positions.size();
    for (const uint32_t i : m->mesh.indices) fits = fits && i < n;
    if (!fits) throw std::invalid_argument("Mesh state: arrays that do not make a mesh");
    return m;
}

}  // namespace

void bindStore(pyb::module_& m) {
    pyb::class_<Mesh, std::shared_ptr<Mesh>>(m, "Mesh",
        "A surface: vertices (N, 3) float32 in world space, faces (M, 3) uint32, normals (N, 3)\n"
        "float32, SAGE's sub-pixel points and point_normals (P, 3) float32, and stats (what\n"
        "`vdiso extract --stats` writes). The arrays are views of the mesh's own buffers: no copy.")
        .def_property_readonly("vertices", [](pyb::object self) { return meshArray(self, 0); })
        .def_property_readonly("normals", [](pyb::object self) { return meshArray(self, 1); })
        .def_property_readonly("faces", [](pyb::object self) { return meshArray(self, 2); })
        .def_property_readonly("points", [](pyb::object self) { return meshArray(self, 3); })
        .def_property_readonly("point_normals", [](pyb::object self) { return meshArray(self, 4); })
        .def_readonly("stats", &Mesh::stats)
        .def("write",
             [](const Mesh& mesh, const std::filesystem::path& path, bool overwrite, bool compress) {
                 pyb::gil_scoped_release release;
                 // The arrays are writable views: faces changed in place are checked before a
                 // writer trusts them.
                 const size_t n = mesh.mesh.positions.size();
                 for (size_t k = 0; k < mesh.mesh.indices.size(); ++k)
                     if (mesh.mesh.indices[k] - mesh.mesh.firstVertex >= n)
                         throw std::invalid_argument("Mesh.write: faces[" + std::to_string(k / 3) + "] names vertex " +
                                                     std::to_string(mesh.mesh.indices[k]) + " of " + std::to_string(n));
                 writeMesh(path.string(), mesh.mesh, overwrite, compress, SpaceTransform{});
             },
             "path"_a, pyb::kw_only(), "overwrite"_a = false, "compress"_a = false,
             "Writes the triangles to `path`, the format by its extension (.ply, .stl, .obj, .vtp,\n"
             ".glb); an existing file is refused unless overwrite=True. compress: meshoptimizer\n"
             "compression (.glb only).")
        .def("write_points",
             [](const Mesh& mesh, const std::filesystem::path& path, bool overwrite) {
                 pyb::gil_scoped_release release;
                 writePointsPly(path.string(), mesh.points, overwrite, SpaceTransform{});
             },
             "path"_a, pyb::kw_only(), "overwrite"_a = false, "Writes the sub-pixel points as a .ply file.")
        .def("__len__", [](const Mesh& mesh) { return mesh.mesh.triangleCount(); }, "The number of triangles.")
        .def(pyb::pickle([](const Mesh& mesh) { return meshState(mesh); }, [](const pyb::tuple& state) {
            return meshFromState(state);
        }))
        .def("__repr__", [](const Mesh& mesh) {
            return "<vdiso.Mesh: " + std::to_string(mesh.mesh.triangleCount()) + " triangles, " +
                   std::to_string(mesh.mesh.vertexCount()) + " vertices, " + std::to_string(mesh.points.size()) +
                   " points>";
        });

    pyb::class_<Store>(m, "_Store")
        .def(pyb::init([](const std::string& path, const std::string& s3Endpoint, bool anonymous,
                          const std::string& diskCache) {
                 pyb::gil_scoped_release release;
                 return Store{std::make_shared<BrickStoreReader>(
                     path, StoreOpenOptions{ReadMode::Buffered, remoteOptions(s3Endpoint, anonymous, diskCache)})};
             }),
             "path"_a, "s3_endpoint"_a = "", "anonymous"_a = false, "disk_cache"_a = "")
        .def_property_readonly("path", [](const Store& s) { return s.reader->path(); })
        .def_property_readonly("dims", [](const Store& s) {
            const Dims3& d = s.reader->volume().dims;
            return pyb::make_tuple(d[0], d[1], d[2]);
        })
        .def_property_readonly("dtype", [](const Store& s) { return dtypeOf(s.reader->volume().type); })
        .def_property_readonly("spacing_xyz", [](const Store& s) { return vec(s.reader->volume().spacing); })
        .def_property_readonly("origin_xyz", [](const Store& s) { return vec(s.reader->volume().origin); })
        .def_property_readonly("direction", [](const Store& s) -> pyb::object {
            const VolumeInfo& v = s.reader->volume();
            if (!v.hasOrientation) return pyb::none();
            pyb::array_t<double> d({3, 3});
            for (int r = 0; r < 3; ++r)
                for (int c = 0; c < 3; ++c) d.mutable_at(r, c) = v.direction[c][r];
            return d;
        })
        .def_property_readonly("levels", [](const Store& s) { return s.reader->header().levelCount; })
        .def_property_readonly("value_range", [](const Store& s) {
            return pyb::make_tuple(s.reader->header().valueMin, s.reader->header().valueMax);
        })
        .def("histogram", [](const Store& s) {
            const ValueHistogram& h = s.reader->histogram();
            pyb::array_t<uint64_t> counts(kHistogramBins);
            pyb::array_t<double> edges(kHistogramBins + 1);
            for (int b = 0; b < kHistogramBins; ++b) counts.mutable_at(b) = h.counts[size_t(b)];
            for (int b = 0; b <= kHistogramBins; ++b) edges.mutable_at(b) = h.lo + (h.hi - h.lo) * b / kHistogramBins;
            return pyb::make_tuple(counts, edges);
        })
        .def("info_json", [](const Store& s, std::optional<double> iso) { return storeInfoJson(*s.reader, iso).str(); },
             "iso"_a = pyb::none());

    // A camera crosses from Python as this struct, made from vdiso.Camera's fields or a dict's
    // and checked once, by core/camera.h's cameraProblem.
    pyb::class_<Camera>(m, "_Camera")
        .def(pyb::init([](std::array<double, 3> eye, std::array<double, 3> target, std::array<double, 3> up,
                          double fov, int width, int height, std::optional<double> near, std::optional<double> far) {
                 Camera c;
                 c.eye = {eye[0], eye[1], eye[2]};
                 c.target = {target[0], target[1], target[2]};
                 c.up = {up[0], up[1], up[2]};
                 c.fovYDegrees = fov;
                 c.width = width;
                 c.height = height;
                 if (near.has_value() != far.has_value()) throw std::invalid_argument("camera: near and far go together");
                 if (near) {
                     c.zNear = *near;
                     c.zFar = *far;
                 }
                 if (const std::string problem = cameraProblem(c); !problem.empty())
                     throw std::invalid_argument("camera: " + problem);  // a ValueError
                 return c;
             }),
             "eye"_a, "target"_a, "up"_a, "fov"_a, "width"_a, "height"_a, "near"_a = pyb::none(), "far"_a = pyb::none());

    pyb::class_<Session>(m, "_Session")
        .def(pyb::init([](const Store& store, const std::string& method, double iso, std::optional<double> lodError,
                          int64_t threads, std::optional<int64_t> cacheMb, bool largest, int64_t minPiece, int64_t smooth, double decimate,
                          bool volumeSpace) {
                 ExtractSettings s = settingsOf(method, iso, lodError, threads, cacheMb, largest, minPiece, smooth,
                                                decimate, volumeSpace);
                 pyb::gil_scoped_release release;
                 return std::make_unique<Session>(store, std::move(s));
             }),
             "store"_a, "method"_a, "iso"_a, "lod_error"_a, "threads"_a, "cache_mb"_a, "largest"_a, "min_piece"_a,
             "smooth"_a, "decimate"_a, "volume_space"_a)
        .def("configure",
             [](Session& self, const std::string& method, double iso, std::optional<double> lodError, int64_t threads,
                std::optional<int64_t> cacheMb, bool largest, int64_t minPiece, int64_t smooth, double decimate, bool volumeSpace) {
                 ExtractSettings s = settingsOf(method, iso, lodError, threads, cacheMb, largest, minPiece, smooth,
                                                decimate, volumeSpace);
                 pyb::gil_scoped_release release;
                 self.configure(std::move(s));
             },
             "method"_a, "iso"_a, "lod_error"_a, "threads"_a, "cache_mb"_a, "largest"_a, "min_piece"_a, "smooth"_a,
             "decimate"_a, "volume_space"_a)
        .def("extract", &Session::extract, "camera"_a, "view"_a, "width"_a, "height"_a, "progress"_a = pyb::none())
        .def("render", &Session::render, "camera"_a, "view"_a, "width"_a, "height"_a);
}

}  // namespace vdiso::py

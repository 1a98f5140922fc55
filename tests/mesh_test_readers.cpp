#include "tests/mesh_test_readers.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <map>
#include <sstream>

#include <glm/geometric.hpp>
#include <meshoptimizer.h>

#include "tests/test_util.h"

namespace vdiso::test {

namespace {

template <class T>
T load(const std::vector<unsigned char>& bytes, uint64_t at) {
    T value{};
    EXPECT_LE(at + sizeof(T), bytes.size());
    if (at + sizeof(T) <= bytes.size()) std::memcpy(&value, bytes.data() + at, sizeof(T));
    return value;
}

// `count` elements of `bytes` from `at`, or none if they are not all there.
template <class Array>
void loadArray(const std::vector<unsigned char>& bytes, uint64_t at, size_t count, Array& out) {
    using T = typename Array::value_type;
    out.clear();
    EXPECT_LE(at + count * sizeof(T), bytes.size());
    if (at + count * sizeof(T) > bytes.size()) return;
    out.resize(count);
    if (count > 0) std::memcpy(out.data(), bytes.data() + at, count * sizeof(T));  // data() may be null
}

// The value of attribute `name` in `tag` (name="value").
std::string attribute(const std::string& tag, const std::string& name) {
    const size_t at = tag.find(" " + name + "=\"");
    if (at == std::string::npos) return "";
    const size_t begin = at + name.size() + 3;
    return tag.substr(begin, tag.find('"', begin) - begin);
}

}  // namespace

TriangleMesh readPly(const std::string& path) {
    const auto bytes = readFile(path);
    const std::string text(bytes.begin(), bytes.end());
    const size_t end = text.find("end_header\n");
    EXPECT_NE(end, std::string::npos);
    std::istringstream header(text.substr(0, end));
    std::string line;
    size_t vertices = 0, faces = 0;
    while (std::getline(header, line)) {
        std::istringstream words(line);
        std::string a, b;
        size_t n = 0;
        words >> a >> b >> n;
        if (a == "element" && b == "vertex") vertices = n;
        if (a == "element" && b == "face") faces = n;
    }
    TriangleMesh m;
    const unsigned char* p = bytes.data() + end + std::strlen("end_header\n");
    for (size_t i = 0; i < vertices; ++i, p += 24) {
        float v[6];
        std::memcpy(v, p, 24);
        m.positions.push_back({v[0], v[1], v[2]});
        m.normals.push_back({v[3], v[4], v[5]});
    }
    for (size_t f = 0; f < faces; ++f, p += 13) {
        EXPECT_EQ(p[0], 3);
        uint32_t idx[3];
        std::memcpy(idx, p + 1, 12);
        m.indices.insert(m.indices.end(), idx, idx + 3);
    }
    EXPECT_EQ(size_t(p - bytes.data()), bytes.size()) << "trailing bytes";
    return m;
}

StlTriangles readStl(const std::string& path) {
    const auto bytes = readFile(path);
    StlTriangles stl;
    EXPECT_GE(bytes.size(), 84u);
    if (bytes.size() < 84) return stl;
    EXPECT_NE(std::string(bytes.begin(), bytes.begin() + 5), "solid") << "reads as ASCII STL";
    const auto count = load<uint32_t>(bytes, 80);
    EXPECT_EQ(bytes.size(), 84 + 50 * uint64_t(count));
    for (uint64_t t = 0, at = 84; t < count && at + 50 <= bytes.size(); ++t, at += 50) {
        float v[12];
        std::memcpy(v, bytes.data() + at, sizeof v);
        stl.normals.push_back({v[0], v[1], v[2]});
        for (int k = 0; k < 3; ++k) stl.corners.push_back({v[3 + 3 * k], v[4 + 3 * k], v[5 + 3 * k]});
        EXPECT_EQ(load<uint16_t>(bytes, at + 48), 0u);
    }
    return stl;
}

TriangleMesh readGlb(const std::string& path, nlohmann::json* jsonOut) {
    const auto bytes = readFile(path);
    TriangleMesh m;
    EXPECT_GE(bytes.size(), 20u);
    if (bytes.size() < 20) return m;
    EXPECT_EQ(load<uint32_t>(bytes, 0), 0x46546C67u) << "magic glTF";
    EXPECT_EQ(load<uint32_t>(bytes, 4), 2u) << "version";
    EXPECT_EQ(load<uint32_t>(bytes, 8), bytes.size()) << "length";
    EXPECT_EQ(bytes.size() % 4, 0u);
    const auto jsonBytes = load<uint32_t>(bytes, 12);
    EXPECT_EQ(load<uint32_t>(bytes, 16), 0x4E4F534Au) << "JSON chunk first";
    EXPECT_EQ(jsonBytes % 4, 0u) << "JSON chunk padded to 4 bytes";
    EXPECT_LE(20 + uint64_t(jsonBytes), bytes.size());
    if (20 + uint64_t(jsonBytes) > bytes.size()) return m;
    const std::string text(bytes.begin() + 20, bytes.begin() + 20 + jsonBytes);
    EXPECT_EQ(text.find_last_not_of(' ') + 1, text.find_last_of('}') + 1) << "padded with spaces";
    const nlohmann::json gltf = nlohmann::json::parse(text);
    if (jsonOut) *jsonOut = gltf;
    EXPECT_EQ(gltf["asset"]["version"], "2.0");
    std::vector<unsigned char> bin;
    const uint64_t binAt = 20 + uint64_t(jsonBytes);
    if (binAt < bytes.size()) {
        const auto binBytes = load<uint32_t>(bytes, binAt);
        EXPECT_EQ(load<uint32_t>(bytes, binAt + 4), 0x004E4942u) << "BIN chunk";
        EXPECT_EQ(binBytes % 4, 0u) << "BIN chunk padded to 4 bytes";
        EXPECT_EQ(binAt + 8 + binBytes, bytes.size());
        loadArray(bytes, binAt + 8, binBytes, bin);
        EXPECT_LE(gltf["buffers"][0]["byteLength"].get<uint64_t>(), bin.size());
    }
    if (!gltf.contains("meshes")) return m;  // an empty mesh
    EXPECT_EQ(gltf["scenes"][gltf["scene"].get<size_t>()]["nodes"], nlohmann::json::array({0}));
    EXPECT_EQ(gltf["nodes"][0]["mesh"], 0);
    EXPECT_EQ(gltf["meshes"].size(), 1u);
    const nlohmann::json& primitive = gltf["meshes"][0]["primitives"][0];
    EXPECT_EQ(primitive["mode"], 4);
    // The accessor's data: its buffer view, decoded if compressed.
    auto viewData = [&](const nlohmann::json& accessor) {
        const nlohmann::json& view = gltf["bufferViews"][accessor["bufferView"].get<size_t>()];
        const uint64_t length = view["byteLength"];
        std::vector<unsigned char> data;
        if (!view.contains("extensions")) {
            EXPECT_EQ(view["buffer"], 0);
            loadArray(bin, view.value("byteOffset", uint64_t(0)), length, data);
            return data;
        }
        const nlohmann::json& ext = view["extensions"]["EXT_meshopt_compression"];
        EXPECT_EQ(ext["buffer"], 0);
        const nlohmann::json& fallback = gltf["buffers"][view["buffer"].get<size_t>()];
        EXPECT_TRUE(fallback["extensions"]["EXT_meshopt_compression"]["fallback"].get<bool>());
        EXPECT_FALSE(fallback.contains("uri"));
        EXPECT_LE(view.value("byteOffset", uint64_t(0)) + length, fallback["byteLength"].get<uint64_t>());
        const uint64_t count = ext["count"], stride = ext["byteStride"];
        EXPECT_EQ(count * stride, length);
        std::vector<unsigned char> packed;
        loadArray(bin, ext.value("byteOffset", uint64_t(0)), ext["byteLength"].get<size_t>(), packed);
        data.resize(length);
        const int status =
            ext["mode"] == "TRIANGLES"
                ? meshopt_decodeIndexBuffer(data.data(), count, stride, packed.data(), packed.size())
                : meshopt_decodeVertexBuffer(data.data(), count, stride, packed.data(), packed.size());
        EXPECT_EQ(ext["mode"], accessor["type"] == "SCALAR" ? "TRIANGLES" : "ATTRIBUTES");
        EXPECT_EQ(status, 0) << "meshopt decoding";
        return data;
    };
    const nlohmann::json& position = gltf["accessors"][primitive["attributes"]["POSITION"].get<size_t>()];
    const nlohmann::json& normal = gltf["accessors"][primitive["attributes"]["NORMAL"].get<size_t>()];
    const nlohmann::json& indices = gltf["accessors"][primitive["indices"].get<size_t>()];
    for (const nlohmann::json* a : {&position, &normal}) {
        EXPECT_EQ((*a)["componentType"], 5126);
        EXPECT_EQ((*a)["type"], "VEC3");
    }
    EXPECT_EQ(indices["componentType"], 5125);
    EXPECT_EQ(indices["type"], "SCALAR");
    const size_t vertices = position["count"];
    EXPECT_EQ(normal["count"], vertices);
    loadArray(viewData(position), 0, vertices, m.positions);
    loadArray(viewData(normal), 0, vertices, m.normals);
    loadArray(viewData(indices), 0, indices["count"].get<size_t>(), m.indices);
    glm::vec3 lo(INFINITY), hi(-INFINITY);
    for (const glm::vec3& p : m.positions) {
        lo = glm::min(lo, p);
        hi = glm::max(hi, p);
    }
    for (int k = 0; k < 3; ++k) {
        EXPECT_EQ(position["min"][k].get<float>(), lo[k]) << k;
        EXPECT_EQ(position["max"][k].get<float>(), hi[k]) << k;
    }
    return m;
}

TriangleMesh readVtp(const std::string& path) {
    const auto bytes = readFile(path);
    const std::string text(bytes.begin(), bytes.end());
    TriangleMesh m;
    const size_t appended = text.find("<AppendedData encoding=\"raw\">");
    EXPECT_NE(appended, std::string::npos);
    if (appended == std::string::npos) return m;
    const std::string xml = text.substr(0, appended);
    const size_t start = text.find('_', appended) + 1;  // the offsets count from here
    const size_t fileTag = xml.find("<VTKFile");
    const std::string vtkFile = xml.substr(fileTag, xml.find('>', fileTag) - fileTag);
    EXPECT_EQ(attribute(vtkFile, "type"), "PolyData");
    EXPECT_EQ(attribute(vtkFile, "byte_order"), "LittleEndian");
    EXPECT_EQ(attribute(vtkFile, "header_type"), "UInt64");
    const size_t pieceAt = xml.find("<Piece");
    const std::string piece = xml.substr(pieceAt, xml.find('>', pieceAt) - pieceAt);
    const size_t points = std::stoull(attribute(piece, "NumberOfPoints"));
    const size_t polys = std::stoull(attribute(piece, "NumberOfPolys"));
    EXPECT_NE(xml.find("<PointData Normals=\"Normals\">"), std::string::npos);
    // Every DataArray by name: its type and where its block is.
    std::map<std::string, std::string> arrays;
    for (size_t at = xml.find("<DataArray"); at != std::string::npos; at = xml.find("<DataArray", at + 1)) {
        const std::string tag = xml.substr(at, xml.find('>', at) - at);
        EXPECT_EQ(attribute(tag, "format"), "appended");
        arrays[attribute(tag, "Name")] = tag;
    }
    auto block = [&](const std::string& name, const char* type, size_t count, auto& out) {
        const std::string& tag = arrays[name];
        EXPECT_EQ(attribute(tag, "type"), type) << name;
        const uint64_t at = start + std::stoull(attribute(tag, "offset"));
        EXPECT_EQ(load<uint64_t>(bytes, at), count * sizeof(out[0])) << name << " block size";
        loadArray(bytes, at + 8, count, out);
    };
    block("Points", "Float32", points, m.positions);
    block("Normals", "Float32", points, m.normals);
    EXPECT_EQ(attribute(arrays["Points"], "NumberOfComponents"), "3");
    EXPECT_EQ(attribute(arrays["Normals"], "NumberOfComponents"), "3");
    std::vector<int64_t> connectivity, offsets;
    block("connectivity", "Int64", 3 * polys, connectivity);
    block("offsets", "Int64", polys, offsets);
    for (size_t t = 0; t < offsets.size(); ++t) EXPECT_EQ(offsets[t], int64_t(3 * (t + 1))) << t;
    m.indices.assign(connectivity.begin(), connectivity.end());
    EXPECT_NE(text.find("</AppendedData>\n</VTKFile>", start), std::string::npos);
    return m;
}

void expectSameMesh(const TriangleMesh& actual, const TriangleMesh& expected, const std::string& what,
                    bool rotated) {
    EXPECT_EQ(actual.triangleCount(), expected.triangleCount()) << what;
    EXPECT_TRUE(actual.positions == expected.positions) << what << ": positions differ";
    EXPECT_TRUE(actual.normals == expected.normals) << what << ": normals differ";
    if (!rotated || actual.indices.size() != expected.indices.size()) {
        EXPECT_TRUE(actual.indices == expected.indices) << what << ": indices differ";
        return;
    }
    size_t differ = 0;
    for (size_t t = 0; t < expected.triangleCount(); ++t) {
        const uint32_t* a = &actual.indices[3 * t];
        const uint32_t* e = &expected.indices[3 * t];
        bool same = false;
        for (int r = 0; r < 3; ++r) same |= a[r] == e[0] && a[(r + 1) % 3] == e[1] && a[(r + 2) % 3] == e[2];
        differ += !same;
    }
    EXPECT_EQ(differ, 0u) << what << ": triangles differ";
}

void expectSameTriangles(const StlTriangles& actual, const TriangleMesh& expected,
                         const std::string& what) {
    ASSERT_EQ(actual.normals.size(), expected.triangleCount()) << what;
    ASSERT_EQ(actual.corners.size(), expected.indices.size()) << what;
    size_t differ = 0, notUnit = 0;
    for (size_t i = 0; i < expected.indices.size(); ++i)
        differ += actual.corners[i] != expected.positions[expected.indices[i]];
    for (const glm::vec3& n : actual.normals) notUnit += !(std::abs(glm::length(n) - 1.0f) < 1e-5f);
    EXPECT_EQ(differ, 0u) << what << ": corners differ";
    EXPECT_EQ(notUnit, 0u) << what << ": normals not unit length";
}

}  // namespace vdiso::test

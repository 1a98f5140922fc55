// Mesh files: PLY parsed back equals the mesh, streamed or whole; OBJ has every vertex,
// normal and face; nothing is left behind on failure.
#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <sstream>

#include "io/error.h"
#include "io/mesh_writer.h"
#include "tests/test_util.h"

namespace vdiso {
namespace {

TriangleMesh testMesh(uint32_t vertices, uint32_t firstVertex = 0) {
    TriangleMesh m;
    m.firstVertex = firstVertex;
    for (uint32_t i = 0; i < vertices; ++i) {
        m.positions.push_back({float(i), float(i) * 0.5f, -float(i)});
        m.normals.push_back({0.0f, 0.0f, 1.0f});
    }
    for (uint32_t i = 0; i + 2 < vertices; ++i)
        m.indices.insert(m.indices.end(), {firstVertex + i, firstVertex + i + 1, firstVertex + i + 2});
    return m;
}

// Parses a binary PLY as vdiso writes it.
TriangleMesh readPly(const std::string& path) {
    const auto bytes = test::readFile(path);
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

TEST(MeshWriter, PlyRoundTripWholeAndStreamed) {
    test::ScratchDir dir;
    const TriangleMesh whole = testMesh(1000);
    writeMesh(dir.file("whole.ply"), whole, false);
    const TriangleMesh back = readPly(dir.file("whole.ply"));
    EXPECT_EQ(back.positions, whole.positions);
    EXPECT_EQ(back.normals, whole.normals);
    EXPECT_EQ(back.indices, whole.indices);

    // Three pieces, triangles of a later piece referring to earlier vertices.
    MeshFileWriter writer(dir.file("streamed.ply"), false);
    TriangleMesh a = testMesh(400), b = testMesh(300, 400), c = testMesh(300, 700);
    b.indices.insert(b.indices.end(), {0, 399, 400});
    writer.append(a);
    writer.append(b);
    writer.append(c);
    EXPECT_FALSE(std::filesystem::exists(dir.file("streamed.ply")));  // not before finish()
    writer.finish();
    const TriangleMesh streamed = readPly(dir.file("streamed.ply"));
    EXPECT_EQ(streamed.positions.size(), 1000u);
    EXPECT_EQ(streamed.indices.size(), a.indices.size() + b.indices.size() + c.indices.size());
    EXPECT_EQ(writer.triangles(), streamed.triangleCount());
    EXPECT_EQ(std::distance(std::filesystem::directory_iterator(dir.path()),
                            std::filesystem::directory_iterator()),
              2);  // whole.ply, streamed.ply: no side file left
}

TEST(MeshWriter, ObjHasEveryVertexNormalAndFace) {
    test::ScratchDir dir;
    writeMesh(dir.file("m.obj"), testMesh(50), false);
    const auto bytes = test::readFile(dir.file("m.obj"));
    std::istringstream in(std::string(bytes.begin(), bytes.end()));
    std::string line;
    int v = 0, vn = 0, f = 0;
    while (std::getline(in, line)) {
        v += line.rfind("v ", 0) == 0;
        vn += line.rfind("vn ", 0) == 0;
        f += line.rfind("f ", 0) == 0;
    }
    EXPECT_EQ(v, 50);
    EXPECT_EQ(vn, 50);
    EXPECT_EQ(f, 48);
}

TEST(MeshWriter, UnfinishedOrBadOutputsLeaveNothing) {
    test::ScratchDir dir;
    {
        MeshFileWriter writer(dir.file("x.ply"), false);
        writer.append(testMesh(10));
    }  // destroyed without finish(): an interrupted extraction
    EXPECT_TRUE(std::filesystem::is_empty(dir.path()));
    EXPECT_THROW(writeMesh(dir.file("x.stl"), testMesh(3), false), IoError);
    test::writeFile(dir.file("keep.ply"), "old");
    EXPECT_THROW(writeMesh(dir.file("keep.ply"), testMesh(3), false), IoError);
    EXPECT_EQ(test::readFile(dir.file("keep.ply")).size(), 3u);
}

}  // namespace
}  // namespace vdiso

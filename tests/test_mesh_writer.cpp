// Mesh files: every format parsed back equals the mesh, streamed in pieces or whole, from a
// known mesh and from a streamed extraction; STL normals are unit length; GLB's container,
// accessors and compressed views are as glTF and EXT_meshopt_compression say; an empty mesh
// makes a valid file; nothing is left behind on failure and existing files are kept.
#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <functional>
#include <sstream>

#include "core/extract/extract_full.h"
#include "io/error.h"
#include "io/mesh/mesh_writer.h"
#include "tests/extract_test_util.h"
#include "tests/mesh_test_readers.h"
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

// The pieces of a 1000-vertex mesh, triangles of a later piece referring to earlier vertices,
// and the whole mesh they make.
struct Pieces {
    TriangleMesh a = testMesh(400), b = testMesh(300, 400), c = testMesh(300, 700), whole;
    Pieces() {
        b.indices.insert(b.indices.end(), {0, 399, 400});
        c.indices.insert(c.indices.end(), {5, 650, 999});
        for (const TriangleMesh* p : {&a, &b, &c}) {
            whole.positions.insert(whole.positions.end(), p->positions.begin(), p->positions.end());
            whole.normals.insert(whole.normals.end(), p->normals.begin(), p->normals.end());
            whole.indices.insert(whole.indices.end(), p->indices.begin(), p->indices.end());
        }
    }
};

// Writes the pieces to `path`; the file appears only at finish(), with no side file left.
void writePieces(const test::ScratchDir& dir, const std::string& name, const Pieces& pieces,
                 bool compress = false) {
    const auto before = std::distance(std::filesystem::directory_iterator(dir.path()),
                                      std::filesystem::directory_iterator());
    MeshFileWriter writer(dir.file(name), false, compress);
    writer.append(pieces.a);
    writer.append(pieces.b);
    writer.append(pieces.c);
    EXPECT_FALSE(std::filesystem::exists(dir.file(name)));  // not before finish()
    writer.finish();
    EXPECT_EQ(writer.triangles(), pieces.whole.triangleCount());
    EXPECT_EQ(writer.vertices(), 1000u);
    EXPECT_EQ(std::distance(std::filesystem::directory_iterator(dir.path()),
                            std::filesystem::directory_iterator()),
              before + 1)
        << name << ": a side file left";
}

// The indexed formats read back give the mesh bit for bit.
TEST(MeshWriter, PlyGlbVtpRoundTripWholeAndStreamed) {
    test::ScratchDir dir;
    const TriangleMesh whole = testMesh(1000);
    const Pieces pieces;
    const std::pair<std::string, std::function<TriangleMesh(const std::string&)>> formats[] = {
        {".ply", test::readPly},
        {".glb", [](const std::string& path) { return test::readGlb(path); }},
        {".vtp", test::readVtp}};
    for (const auto& [extension, read] : formats) {
        writeMesh(dir.file("whole" + extension), whole, false);
        test::expectSameMesh(read(dir.file("whole" + extension)), whole, "whole" + extension);
        writePieces(dir, "streamed" + extension, pieces);
        test::expectSameMesh(read(dir.file("streamed" + extension)), pieces.whole, "streamed" + extension);
    }
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

TEST(MeshWriter, StlHasEveryTriangleWithUnitNormals) {
    test::ScratchDir dir;
    // The test mesh's triangles have no area (its vertices are on a line): their facet normal is
    // their vertices' normal.
    const Pieces pieces;
    writePieces(dir, "streamed.stl", pieces);
    const test::StlTriangles stl = test::readStl(dir.file("streamed.stl"));
    test::expectSameTriangles(stl, pieces.whole, "streamed");
    for (const glm::vec3& n : stl.normals) EXPECT_EQ(n, glm::vec3(0, 0, 1));
    // A triangle with area: its own normal, counter-clockwise, whatever the vertex normals.
    TriangleMesh t;
    t.positions = {{0, 0, 0}, {2, 0, 0}, {0, 3, 0}};
    t.normals = {{1, 0, 0}, {1, 0, 0}, {1, 0, 0}};
    t.indices = {0, 1, 2, 0, 2, 1};
    writeMesh(dir.file("t.stl"), t, false);
    const test::StlTriangles back = test::readStl(dir.file("t.stl"));
    test::expectSameTriangles(back, t, "two triangles");
    ASSERT_EQ(back.normals.size(), 2u);
    EXPECT_EQ(back.normals[0], glm::vec3(0, 0, 1));
    EXPECT_EQ(back.normals[1], glm::vec3(0, 0, -1));
}

TEST(MeshWriter, GlbAccessorsCountAndBound) {
    test::ScratchDir dir;
    writeMesh(dir.file("whole.glb"), testMesh(1000), false);
    nlohmann::json json;
    test::readGlb(dir.file("whole.glb"), &json);  // checks the container on the way
    EXPECT_EQ(json["accessors"][0]["count"], 1000);
    EXPECT_EQ(json["accessors"][2]["count"], 998 * 3);
    EXPECT_EQ(json["accessors"][0]["min"], nlohmann::json::array({0.0, 0.0, -999.0}));
    EXPECT_EQ(json["accessors"][0]["max"], nlohmann::json::array({999.0, 499.5, 0.0}));
    EXPECT_FALSE(json.contains("extensionsUsed"));
}

TEST(MeshWriter, CompressedGlbDecodesToTheMesh) {
    test::ScratchDir dir;
    const Pieces pieces;
    writePieces(dir, "packed.glb", pieces, true);
    nlohmann::json json;
    test::expectSameMesh(test::readGlb(dir.file("packed.glb"), &json), pieces.whole, "compressed", true);
    for (const char* key : {"extensionsUsed", "extensionsRequired"})
        EXPECT_EQ(json[key], nlohmann::json::array({"EXT_meshopt_compression"})) << key;
    ASSERT_EQ(json["bufferViews"].size(), 3u);
    for (const nlohmann::json& view : json["bufferViews"])
        EXPECT_TRUE(view["extensions"].contains("EXT_meshopt_compression")) << view;
    ASSERT_EQ(json["buffers"].size(), 2u);
    // Smaller than the plain file.
    writePieces(dir, "plain.glb", pieces);
    EXPECT_LT(test::readFile(dir.file("packed.glb")).size(),
              test::readFile(dir.file("plain.glb")).size());
}

// A full extraction streamed in many pieces (seams welded to vertices of earlier pieces)
// writes in every format the mesh extracted held in memory.
TEST(MeshWriter, EveryFormatFromAStreamedExtraction) {
    test::ScratchDir dir;
    SynthParams p;
    p.kind = SynthKind::Head;
    p.dims = {48, 44, 40};
    auto source = test::synthBrickSource(p, 8);
    TriangleMesh held;
    extractOctree(*source, {kHeadSkinIso, 4, 1}, held);
    ASSERT_GT(held.triangleCount(), 1000u);
    for (const char* name : {"h.ply", "h.stl", "h.glb", "packed.glb", "h.vtp"}) {
        const bool compress = std::string(name) == "packed.glb";
        MeshFileWriter writer(dir.file(name), false, compress);
        FullExtractOptions o{kHeadSkinIso, 4, 1};
        o.sink = &writer;
        o.streamPieceVertices = 500;
        TriangleMesh rest;
        extractOctree(*source, o, rest);
        writer.finish();
        EXPECT_EQ(writer.triangles(), held.triangleCount()) << name;
    }
    test::expectSameMesh(test::readPly(dir.file("h.ply")), held, "PLY");
    test::expectSameTriangles(test::readStl(dir.file("h.stl")), held, "STL");
    test::expectSameMesh(test::readGlb(dir.file("h.glb")), held, "GLB");
    test::expectSameMesh(test::readGlb(dir.file("packed.glb")), held, "compressed GLB", true);
    test::expectSameMesh(test::readVtp(dir.file("h.vtp")), held, "VTP");
    // STL's facet normals face the way the vertex normals do (the surface's outside).
    const test::StlTriangles stl = test::readStl(dir.file("h.stl"));
    size_t agree = 0;
    for (size_t t = 0; t < held.triangleCount(); ++t)
        agree += glm::dot(stl.normals[t], held.normals[held.indices[3 * t]]) > 0;
    EXPECT_GT(agree, held.triangleCount() * 95 / 100);
}

TEST(MeshWriter, EmptyMeshInEveryFormat) {
    test::ScratchDir dir;
    const TriangleMesh empty;
    for (const char* name : {"e.ply", "e.obj", "e.stl", "e.glb", "e.vtp"})
        writeMesh(dir.file(name), empty, false);
    writeMesh(dir.file("packed.glb"), empty, false, true);
    EXPECT_EQ(test::readPly(dir.file("e.ply")).positions.size(), 0u);
    EXPECT_EQ(test::readStl(dir.file("e.stl")).normals.size(), 0u);
    EXPECT_EQ(test::readVtp(dir.file("e.vtp")).positions.size(), 0u);
    for (const char* name : {"e.glb", "packed.glb"}) {
        nlohmann::json json;
        EXPECT_EQ(test::readGlb(dir.file(name), &json).positions.size(), 0u);
        EXPECT_EQ(json["nodes"].size(), 1u) << name;
        EXPECT_FALSE(json.contains("extensionsRequired")) << name;
    }
}

TEST(MeshWriter, UnfinishedOrBadOutputsLeaveNothing) {
    test::ScratchDir dir;
    for (const char* name : {"x.ply", "x.stl", "x.glb", "x.vtp"}) {
        MeshFileWriter writer(dir.file(name), false, std::string(name) == "x.glb");
        writer.append(testMesh(10));
    }  // destroyed without finish(): an interrupted extraction
    EXPECT_TRUE(std::filesystem::is_empty(dir.path()));
    try {
        writeMesh(dir.file("x.stp"), testMesh(3), false);
        ADD_FAILURE() << "an unknown extension was accepted";
    } catch (const IoError& e) {
        EXPECT_NE(std::string(e.what()).find("x.stp: unknown mesh format"), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find(".ply, .obj, .stl, .glb or .vtp"), std::string::npos) << e.what();
    }
    EXPECT_THROW(writeMesh(dir.file("x.ply"), testMesh(3), false, true), IoError);  // compressed
    EXPECT_TRUE(std::filesystem::is_empty(dir.path()));
    for (const char* name : {"keep.ply", "keep.obj", "keep.stl", "keep.glb", "keep.vtp"}) {
        test::writeFile(dir.file(name), "old");
        EXPECT_THROW(writeMesh(dir.file(name), testMesh(3), false), IoError) << name;
        EXPECT_EQ(test::readFile(dir.file(name)).size(), 3u) << name;
    }
}

}  // namespace
}  // namespace vdiso

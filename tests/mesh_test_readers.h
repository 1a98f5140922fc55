// Test support: mesh files as vdiso writes them, parsed back (PLY, STL, GLB with or without
// EXT_meshopt_compression, VTP), checking their layout with gtest expectations on the way.
#pragma once

#include <string>
#include <vector>

#include <glm/vec3.hpp>
#include <nlohmann/json.hpp>

#include "core/mesh.h"

namespace vdiso::test {

TriangleMesh readPly(const std::string& path);

struct StlTriangles {
    std::vector<glm::vec3> normals;  // one per triangle
    std::vector<glm::vec3> corners;  // three per triangle
};
StlTriangles readStl(const std::string& path);

// Checks the GLB container (magic, version, length, chunk types and 4-byte alignment) and the
// accessors (counts, POSITION's min and max); decodes compressed views with meshoptimizer.
// `json` receives the JSON chunk.
TriangleMesh readGlb(const std::string& path, nlohmann::json* json = nullptr);

TriangleMesh readVtp(const std::string& path);

// Same vertices, normals and triangles, bit for bit; with `rotated`, a triangle's corners may
// start at another one of them (same winding), as meshoptimizer's index codec leaves them.
void expectSameMesh(const TriangleMesh& actual, const TriangleMesh& expected, const std::string& what,
                    bool rotated = false);
// The STL triangles are the mesh's (corners bit for bit), with unit normals.
void expectSameTriangles(const StlTriangles& actual, const TriangleMesh& expected,
                         const std::string& what);

}  // namespace vdiso::test

// Orientation end to end, apart from the readers (their tests hold theirs): the store keeps the
// direction matrix and flag (format 4) and opens older stores as unoriented; meshes are written
// in physical space in every format, streamed or whole, with normals and winding that stay
// outward and counter-clockwise through a mirroring direction; presets look at the patient's
// sides; and the command line's --mesh-space, --view and info.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <string>

#include <glm/geometric.hpp>
#include <glm/matrix.hpp>
#include <nlohmann/json.hpp>

#include "core/camera.h"
#include "core/extract/extract_full.h"
#include "core/orientation.h"
#include "core/view_presets.h"
#include "io/crc32.h"
#include "io/store/brick_store.h"
#include "io/mesh/mesh_writer.h"
#include "io/store/store_format.h"
#include "io/store/store_writer.h"
#include "tests/extract_test_util.h"
#include "tests/mesh_test_readers.h"
#include "tests/reader_test_util.h"
#include "tests/test_util.h"

namespace vdiso {
namespace {

using test::ScratchDir;

// A quarter turn about z with k flipped: i -> -y (anterior), j -> +x (left), k -> -z (inferior).
// det = -1: it mirrors.
const glm::dmat3 kTurnAndFlip(0, -1, 0, 1, 0, 0, 0, 0, -1);
// What 3D Slicer calls RAS-stored (ch2.nii.gz): i -> right, j -> anterior, k -> superior.
const glm::dmat3 kRasGrid(-1, 0, 0, 0, -1, 0, 0, 0, 1);

std::string oneLine(const std::exception& e) { return e.what(); }

// ---- the store ----

std::string orientedStore(const ScratchDir& dir, const glm::dmat3& direction) {
    test::MemoryVolume volume({21, 13, 12}, ScalarType::U16);
    volume.orient({5.0, -3.0, 2.0}, direction);
    StoreWriteOptions o;
    o.brickSize = 8;
    const std::string path = dir.file("oriented.vdiso");
    writeBrickStore(volume, path, o);
    return path;
}

TEST(OrientedStore, DirectionAndFlagRoundTrip) {
    ScratchDir dir;
    // Columns not quite unit length (as cosines read from text are): stored normalised.
    const glm::dmat3 slightlyLong = kTurnAndFlip * 1.0000001;
    const BrickStoreReader store(orientedStore(dir, slightlyLong));
    EXPECT_EQ(store.header().formatVersion, 5u);  // a store holding its samples: version 5 (6 is an index)
    EXPECT_TRUE(store.volume().hasOrientation);
    test::expectDirection(store.volume().direction, kTurnAndFlip, 1e-15);
    EXPECT_EQ(store.volume().origin, glm::dvec3(5.0, -3.0, 2.0));

    test::MemoryVolume plain({21, 13, 12}, ScalarType::U8);
    writeBrickStore(plain, dir.file("plain.vdiso"), {});
    const BrickStoreReader unoriented(dir.file("plain.vdiso"));
    EXPECT_FALSE(unoriented.volume().hasOrientation);
    EXPECT_EQ(unoriented.volume().direction, glm::dmat3(1.0));
}

TEST(OrientedStore, VersionTwoAndThreeStoresOpenWithoutOrientation) {
    ScratchDir dir;
    test::MemoryVolume volume({21, 13, 12}, ScalarType::U16);
    StoreWriteOptions o;
    o.brickSize = 8;
    o.coarseLevels = 0;  // version 2 has level 0 only
    writeBrickStore(volume, dir.file("v4.vdiso"), o);
    const auto current = test::readFile(dir.file("v4.vdiso"));
    for (uint32_t version : {2u, 3u}) {
        SCOPED_TRACE(version);
        const auto bytes = test::storeAsVersion(current, version);
        const std::string old = dir.file("old.vdiso");
        test::writeFile(old, bytes.data(), bytes.size());
        const BrickStoreReader store(old);
        EXPECT_EQ(store.header().formatVersion, version);
        EXPECT_FALSE(store.volume().hasOrientation);
        EXPECT_EQ(store.volume().direction, glm::dmat3(1.0));
        EXPECT_EQ(test::compareStoreWithSamples(store, volume.bytes()), "");
    }
}

TEST(OrientedStore, DamagedOrientationIsRefused) {
    ScratchDir dir;
    const auto good = test::readFile(orientedStore(dir, kTurnAndFlip));
    const std::string bad = dir.file("bad.vdiso");
    // A flipped bit in the direction: the second checksum catches it.
    auto flipped = good;
    flipped[200] ^= 0x10;
    EXPECT_NE(test::storeOpenError(bad, flipped).find("bad.vdiso: header checksum mismatch in its orientation"),
              std::string::npos);
    // Checksums right, contents wrong: a singular direction, a flag of 2, a direction without
    // the flag, a column not of unit length.
    auto rewrite = [&](size_t at, const void* value, size_t n) {
        auto bytes = good;
        std::memcpy(bytes.data() + at, value, n);
        const uint32_t crc = crc32Of(bytes.data(), 240);
        std::memcpy(bytes.data() + 240, &crc, 4);
        return test::storeOpenError(bad, bytes);
    };
    const double column[3] = {0, 1, 0};  // j along i's line (-y)
    EXPECT_NE(rewrite(168 + 24, column, 24).find("orientation is invalid"), std::string::npos);
    const uint32_t two = 2, none = 0;
    EXPECT_NE(rewrite(164, &two, 4).find("orientation flag 2"), std::string::npos);
    EXPECT_NE(rewrite(164, &none, 4).find("no orientation but a direction matrix"), std::string::npos);
    const double longer = -2.0;
    EXPECT_NE(rewrite(168 + 8, &longer, 8).find("not of unit length"), std::string::npos);
}

// ---- meshes in physical space ----

// A closed sphere of radius 7 about the centre of a 24^3 grid at origin (5,-3,2), spacing 1:
// the inside is above the isovalue, so normals point outward.
struct Sphere {
    TriangleMesh mesh;
    VolumeInfo volume;
    glm::dvec3 centre;
};

Sphere sphere(const glm::dmat3& direction) {
    test::MemoryBrickSource source({24, 24, 24}, ScalarType::F32, 8, [](int64_t x, int64_t y, int64_t z) {
        return -test::sphereDistance({24, 24, 24}, x, y, z);
    });
    Sphere s;
    extractOctree(source, {-7.0, 4}, s.mesh);
    s.volume = source.volume();
    s.volume.direction = direction;
    s.volume.hasOrientation = true;
    s.centre = glm::dvec3(11.5);
    return s;
}

// Every vertex is origin + D (p - origin) of its volume-space one, every normal D n (D is
// orthonormal), and the surface stays closed and consistently wound with positive volume:
// outward normals and counter-clockwise faces seen from them.
void expectPhysical(const TriangleMesh& written, const Sphere& s, const std::string& what) {
    SCOPED_TRACE(what);
    ASSERT_EQ(written.positions.size(), s.mesh.positions.size());
    const glm::dmat3& d = s.volume.direction;
    const glm::dvec3 origin = s.volume.origin;
    for (size_t i = 0; i < written.positions.size(); ++i) {
        const glm::dvec3 want = origin + d * (glm::dvec3(s.mesh.positions[i]) - origin);
        ASSERT_LT(glm::length(glm::dvec3(written.positions[i]) - want), 1e-4) << "vertex " << i;
        ASSERT_LT(glm::length(glm::dvec3(written.normals[i]) - d * glm::dvec3(s.mesh.normals[i])), 1e-5)
            << "normal " << i;
    }
    EXPECT_EQ(test::checkClosedOriented(written), "");
    EXPECT_NEAR(test::enclosedVolume(written), test::enclosedVolume(s.mesh), 1e-3 * test::enclosedVolume(s.mesh));
    EXPECT_GT(test::enclosedVolume(written), 0.0);
    // Outward: the normal points away from the physical centre.
    const glm::dvec3 centre = origin + d * (s.centre - origin);
    size_t inward = 0;
    for (size_t i = 0; i < written.positions.size(); ++i)
        if (glm::dot(glm::dvec3(written.normals[i]), glm::dvec3(written.positions[i]) - centre) <= 0) ++inward;
    EXPECT_EQ(inward, 0u);
    // Each triangle's corners turn counter-clockwise about its vertices' normals.
    size_t clockwise = 0;
    for (size_t t = 0; t < written.triangleCount(); ++t) {
        const glm::dvec3 a(written.positions[written.indices[3 * t]]), b(written.positions[written.indices[3 * t + 1]]),
            c(written.positions[written.indices[3 * t + 2]]);
        const glm::dvec3 n(written.normals[written.indices[3 * t]]);
        if (glm::dot(glm::cross(b - a, c - a), n) < 0) ++clockwise;
    }
    EXPECT_LT(clockwise, written.triangleCount() / 100) << "of " << written.triangleCount();
}

TEST(PhysicalMeshes, EveryFormatInPhysicalSpaceThroughAMirror) {
    ScratchDir dir;
    for (const glm::dmat3& d : {kTurnAndFlip, kRasGrid}) {
        const Sphere s = sphere(d);
        ASSERT_GT(s.mesh.triangleCount(), 500u);
        const SpaceTransform t = volumeToPhysical(s.volume);
        EXPECT_EQ(t.mirrors(), glm::determinant(d) < 0);
        writeMesh(dir.file("s.ply"), s.mesh, true, false, t);
        expectPhysical(test::readPly(dir.file("s.ply")), s, "ply");
        writeMesh(dir.file("s.vtp"), s.mesh, true, false, t);
        expectPhysical(test::readVtp(dir.file("s.vtp")), s, "vtp");
        writeMesh(dir.file("s.glb"), s.mesh, true, false, t);
        expectPhysical(test::readGlb(dir.file("s.glb")), s, "glb");
        // STL: the triangles are the transformed mesh's, facet normals outward.
        TriangleMesh mapped = s.mesh;
        transformMesh(t, mapped);
        expectPhysical(mapped, s, "transformMesh");
        writeMesh(dir.file("s.stl"), s.mesh, true, false, t);
        test::expectSameTriangles(test::readStl(dir.file("s.stl")), mapped, "stl");
        // Points: positions and normals alike.
        PointSet points;
        points.positions.assign(s.mesh.positions.begin(), s.mesh.positions.end());
        points.normals.assign(s.mesh.normals.begin(), s.mesh.normals.end());
        writePointsPly(dir.file("p.ply"), points, true, t);
        const TriangleMesh readPoints = test::readPly(dir.file("p.ply"));
        for (size_t i = 0; i < points.size(); ++i) {
            ASSERT_EQ(readPoints.positions[i], mapped.positions[i]);
            ASSERT_EQ(readPoints.normals[i], mapped.normals[i]);
        }
    }
}

// Streamed pieces (triangles welded to vertices of earlier pieces) are mapped like a whole mesh.
TEST(PhysicalMeshes, StreamedPiecesAreMappedAlike) {
    ScratchDir dir;
    const Sphere s = sphere(kTurnAndFlip);
    test::MemoryBrickSource source({24, 24, 24}, ScalarType::F32, 4, [](int64_t x, int64_t y, int64_t z) {
        return -test::sphereDistance({24, 24, 24}, x, y, z);
    });
    VolumeInfo placed = source.volume();
    placed.direction = kTurnAndFlip;
    placed.hasOrientation = true;
    MeshFileWriter writer(dir.file("streamed.ply"), false, false, volumeToPhysical(placed));
    FullExtractOptions o{-7.0, 4, 1};
    o.sink = &writer;
    TriangleMesh rest;
    extractOctree(source, o, rest);
    writer.finish();
    const TriangleMesh streamed = test::readPly(dir.file("streamed.ply"));
    TriangleMesh whole = s.mesh;
    transformMesh(volumeToPhysical(placed), whole);
    EXPECT_EQ(test::canonicalTriangles(streamed), test::canonicalTriangles(whole));
    EXPECT_EQ(test::checkClosedOriented(streamed), "");
    EXPECT_GT(test::enclosedVolume(streamed), 0.0);
}

// A sheared direction: normals follow the inverse transpose, renormalised. For any edge e at a
// vertex with normal n, (D^-T n) . (D e) = n . e: what was perpendicular stays so, exactly.
TEST(PhysicalMeshes, ShearMapsNormalsByTheInverseTranspose) {
    const glm::dmat3 shear(1, 0, 0, 0.6, 0.8, 0, 0, 0, 1);  // j leans towards i
    const Sphere s = sphere(shear);
    const glm::dmat3 normalMap = glm::transpose(glm::inverse(shear));
    TriangleMesh mapped = s.mesh;
    transformMesh(volumeToPhysical(s.volume), mapped);
    for (size_t t = 0; t < mapped.triangleCount(); ++t) {
        const uint32_t a = mapped.indices[3 * t], b = mapped.indices[3 * t + 1];
        const glm::dvec3 n(s.mesh.normals[a]);
        const glm::dvec3 e = glm::dvec3(s.mesh.positions[b]) - glm::dvec3(s.mesh.positions[a]);
        const glm::dvec3 mappedEdge = glm::dvec3(mapped.positions[b]) - glm::dvec3(mapped.positions[a]);
        ASSERT_NEAR(glm::dot(glm::dvec3(mapped.normals[a]), mappedEdge), glm::dot(n, e) / glm::length(normalMap * n), 1e-4);
        ASSERT_NEAR(glm::length(glm::dvec3(mapped.normals[a])), 1.0, 1e-6);
    }
    EXPECT_GT(test::enclosedVolume(mapped), 0.0);
}

// ---- presets ----

TEST(PatientViews, AnteriorLooksAtTheFaceWithSuperiorUp) {
    const glm::dvec3 lo(0.0), hi(180.0, 216.0, 180.0);
    // RAS-stored: anterior is +y in volume space, superior +z (the default's side and up).
    {
        const Camera c = presetCamera(ViewPreset::Normal, patientFacing(PatientSide::Anterior, kRasGrid), lo, hi, 400, 400);
        test::expectDoubleEq(glm::normalize(c.eye - c.target), {0, 1, 0});
        test::expectDoubleEq(c.up, {0, 0, 1});
    }
    // Turned and flipped: anterior (LPS -y) is volume +x, superior (LPS +z) volume -z.
    {
        const Camera c = presetCamera(ViewPreset::Normal, patientFacing(PatientSide::Anterior, kTurnAndFlip), lo, hi, 400, 400);
        test::expectDoubleEq(glm::normalize(c.eye - c.target), {1, 0, 0});
        test::expectDoubleEq(c.up, {0, 0, -1});
        // Mapped to physical space, the eye is in front of the target and up is superior.
        test::expectDoubleEq(kTurnAndFlip * glm::normalize(c.eye - c.target), {0, -1, 0});
    }
    // Every side: the eye lies that way from the target in physical space; up is superior,
    // or anterior looking from above or below.
    const std::pair<PatientSide, glm::dvec3> sides[] = {
        {PatientSide::Anterior, {0, -1, 0}}, {PatientSide::Posterior, {0, 1, 0}}, {PatientSide::Left, {1, 0, 0}},
        {PatientSide::Right, {-1, 0, 0}},    {PatientSide::Superior, {0, 0, 1}},  {PatientSide::Inferior, {0, 0, -1}}};
    for (const auto& [side, lps] : sides) {
        SCOPED_TRACE(patientSideName(side));
        const ViewFacing f = patientFacing(side, kTurnAndFlip);
        for (ViewPreset distance : {ViewPreset::Distant, ViewPreset::Normal, ViewPreset::Closeup}) {
            const Camera c = presetCamera(distance, f, lo, hi, 300, 200);
            test::expectDoubleEq(kTurnAndFlip * glm::normalize(c.eye - c.target), lps);
            const bool vertical = side == PatientSide::Superior || side == PatientSide::Inferior;
            test::expectDoubleEq(kTurnAndFlip * c.up, vertical ? glm::dvec3(0, -1, 0) : glm::dvec3(0, 0, 1));
            // The eye is outside the bounds (closeup included).
            const bool inside = c.eye.x > lo.x && c.eye.x < hi.x && c.eye.y > lo.y && c.eye.y < hi.y &&
                                c.eye.z > lo.z && c.eye.z < hi.z;
            EXPECT_FALSE(inside) << viewPresetName(distance);
        }
    }
    // The default facing is unchanged: the defaulted presetCamera is the explicit one.
    const Camera a = presetCamera(ViewPreset::Closeup, lo, hi, 400, 300);
    const Camera b = presetCamera(ViewPreset::Closeup, defaultFacing(), lo, hi, 400, 300);
    EXPECT_EQ(a.eye, b.eye);
    EXPECT_EQ(a.target, b.target);
}

TEST(PatientViews, DefaultIsAnteriorWithOrientationAndRefusedSidesWithout) {
    VolumeInfo oriented;
    oriented.direction = kTurnAndFlip;
    oriented.hasOrientation = true;
    const ViewFacing f = viewFacing(std::nullopt, oriented);
    test::expectDoubleEq(f.toEye, {1, 0, 0});
    VolumeInfo plain;
    EXPECT_EQ(viewFacing(std::nullopt, plain).toEye, defaultFacing().toEye);
    try {
        viewFacing(PatientSide::Left, plain);
        ADD_FAILURE() << "a side without orientation was accepted";
    } catch (const std::invalid_argument& e) {
        EXPECT_NE(oneLine(e).find("the view 'left' needs a volume with an orientation, and this one has none"),
                  std::string::npos)
            << e.what();
    }
}

TEST(PatientViews, ViewChoicesParse) {
    EXPECT_EQ(parseViewChoice("normal").distance, ViewPreset::Normal);
    EXPECT_FALSE(parseViewChoice("closeup").side);
    EXPECT_EQ(parseViewChoice("anterior").distance, ViewPreset::Normal);
    EXPECT_EQ(parseViewChoice("anterior").side, PatientSide::Anterior);
    const ViewChoice both = parseViewChoice("Inferior,close-up");
    EXPECT_EQ(both.distance, ViewPreset::Closeup);
    EXPECT_EQ(both.side, PatientSide::Inferior);
    EXPECT_EQ(viewChoiceName(both), "closeup,inferior");
    const ViewChoice farther = parseViewChoice("left,2.5");
    EXPECT_EQ(farther.distance, ViewPreset::Normal);
    EXPECT_EQ(farther.times, 2.5);
    EXPECT_EQ(viewChoiceName(farther), "2.5,left");
    EXPECT_EQ(parseViewChoice(viewChoiceName(farther)).times, 2.5);
    // The eye moves along its line to the target, the target stays.
    const glm::dvec3 lo(0.0), hi(100.0, 80.0, 60.0);
    const Camera normal = presetCamera(ViewPreset::Normal, lo, hi, 64, 64);
    const Camera twice = presetCamera(ViewPreset::Normal, defaultFacing(), lo, hi, 64, 64, 2.0);
    EXPECT_EQ(twice.target, normal.target);
    EXPECT_NEAR(glm::length(twice.eye - twice.target), 2.0 * glm::length(normal.eye - normal.target), 1e-9);
    for (const char* bad : {"far", "anterior,left", "normal,distant", "normal,", ",left", "normal,left,right", "",
                            "0", "-2", "2.5x", "nan", "inf", "1e999"}) {
        SCOPED_TRACE(bad);
        EXPECT_THROW(parseViewChoice(bad), std::invalid_argument);
    }
}

TEST(PatientViews, OrbitTurnsAboutUp) {
    const glm::dvec3 lo(0.0), hi(100.0, 80.0, 60.0);
    const ViewFacing f = patientFacing(PatientSide::Superior, kTurnAndFlip);  // up: volume +x
    const std::vector<Camera> orbit = orbitCameras(ViewPreset::Normal, f, lo, hi, 200, 200, 8);
    ASSERT_EQ(orbit.size(), 8u);
    const double distance = glm::length(orbit[0].eye - orbit[0].target);
    for (const Camera& c : orbit) {
        EXPECT_NEAR(glm::length(c.eye - c.target), distance, 1e-9 * distance);
        EXPECT_NEAR(glm::dot(c.eye - c.target, glm::normalize(f.up)), glm::dot(orbit[0].eye - orbit[0].target, glm::normalize(f.up)),
                    1e-9 * distance);
    }
    // Half way round, the eye is on the other side.
    EXPECT_LT(glm::dot(orbit[4].eye - orbit[4].target, orbit[0].eye - orbit[0].target), 0.0);
}

// ---- the command line ----

// A RAS NRRD of a sphere (inside above 100), turned and flipped in RAS.
std::string orientedNrrd(const ScratchDir& dir) {
    const int n = 20;
    std::string samples;
    for (int z = 0; z < n; ++z)
        for (int y = 0; y < n; ++y)
            for (int x = 0; x < n; ++x) {
                const double r = std::sqrt((x - 9.5) * (x - 9.5) + (y - 9.5) * (y - 9.5) + (z - 9.5) * (z - 9.5));
                samples += char(r < 6 ? 200 : 0);
            }
    const std::string path = dir.file("ball.nrrd");
    test::writeFile(path, "NRRD0005\ntype: uchar\ndimension: 3\nspace: RAS\nsizes: 20 20 20\n"
                          "space directions: (0,2,0) (-2,0,0) (0,0,-2)\nspace origin: (10,20,30)\n"
                          "encoding: raw\n\n" + samples);
    return path;
}

TEST(OrientationCli, MeshSpaceViewAndInfo) {
    ScratchDir dir;
    const std::string nrrd = orientedNrrd(dir);
    const std::string store = dir.file("ball.vdiso");
    const auto convert = test::runVdiso("convert " + nrrd + " " + store);
    ASSERT_EQ(convert.exitCode, 0) << convert.output;
    EXPECT_NE(convert.output.find("orientation: axes i, j, k toward ALI"), std::string::npos) << convert.output;

    const auto info = test::runVdiso("info " + store + " --json");
    ASSERT_EQ(info.exitCode, 0) << info.output;
    const auto json = nlohmann::json::parse(info.output);
    EXPECT_EQ(json["format_version"], 5);
    EXPECT_EQ(json["has_orientation"], true);
    EXPECT_EQ(json["axes_toward"], "ALI");
    // RAS (0,1,0) is LPS (0,-1,0): the i axis's direction, first.
    EXPECT_EQ(json["direction"][0], nlohmann::json::parse("[0.0, -1.0, 0.0]")) << info.output;
    const auto text = test::runVdiso("info " + store);
    EXPECT_NE(text.output.find("orientation  axes i, j, k toward ALI"), std::string::npos) << text.output;

    const std::string physical = dir.file("physical.ply"), volume = dir.file("volume.ply");
    auto run = test::runVdiso("extract " + store + " --iso 100 -o " + physical + " --stats -");
    ASSERT_EQ(run.exitCode, 0) << run.output;
    EXPECT_NE(run.output.find("\"mesh_space\": \"physical\""), std::string::npos) << run.output;
    run = test::runVdiso("extract " + store + " --iso 100 -o " + volume + " --mesh-space volume --quiet");
    ASSERT_EQ(run.exitCode, 0) << run.output;
    const TriangleMesh p = test::readPly(physical), v = test::readPly(volume);
    ASSERT_GT(v.triangleCount(), 100u);
    // Volume space is today's output: origin + index * spacing, LPS origin (-10,-20,30).
    const BrickStoreReader reader(store);
    EXPECT_EQ(reader.volume().origin, glm::dvec3(-10, -20, 30));
    TriangleMesh mapped = v;
    transformMesh(volumeToPhysical(reader.volume()), mapped);
    test::expectSameMesh(p, mapped, "physical = volume mapped");
    for (const glm::vec3& q : v.positions)
        for (int a = 0; a < 3; ++a) {
            ASSERT_GE(q[a], reader.volume().origin[a] - 1e-3);
            ASSERT_LE(q[a], reader.volume().worldMax()[a] + 1e-3);
        }

    // --view: a side, a distance and a side; refused on a store without orientation.
    run = test::runVdiso("extract " + store + " --iso 100 --png " + dir.file("a.png") + " --view closeup,left --stats -");
    ASSERT_EQ(run.exitCode, 0) << run.output;
    EXPECT_NE(run.output.find("\"view\": \"closeup,left\""), std::string::npos) << run.output;
    run = test::runVdiso("extract " + store + " --iso 100 --png " + dir.file("b.png") + " --stats -");
    EXPECT_NE(run.output.find("\"view\": \"normal,anterior\""), std::string::npos) << run.output;
    const std::string plain = dir.file("plain.vdiso");
    ASSERT_EQ(test::runVdiso("synth " + plain + " --kind head --size 32 --quiet").exitCode, 0);
    run = test::runVdiso("extract " + plain + " --iso 600.5 --png " + dir.file("c.png") + " --view anterior");
    EXPECT_NE(run.exitCode, 0);
    EXPECT_NE(run.output.find("the view 'anterior' needs a volume with an orientation"), std::string::npos)
        << run.output;
    run = test::runVdiso("extract " + store + " --iso 100 --mesh-space volume");
    EXPECT_NE(run.output.find("--mesh-space applies to mesh outputs"), std::string::npos) << run.output;
}

}  // namespace
}  // namespace vdiso

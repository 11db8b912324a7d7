#include "common/base/mesh.h"

#include <cmath>
#include <limits>
#include <stdexcept>
#include <thread>

#include <gtest/gtest.h>

#include "common/base/errors.h"
#include "tests/mesh_builders.h"

namespace meshmend {
namespace {

TEST(Mesh, MakeMeshRecordsItselfAsOrigin) {
  Mesh m = makeMesh({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, {{0, 1, 2}}, 3);
  ASSERT_EQ(m.vn, 3);
  ASSERT_EQ(m.fn, 1);
  VertexOriginHandle vo = vertexOrigins(m);
  FaceOriginHandle fo = faceOrigins(m);
  EXPECT_EQ(vo[2].layer, 3);
  EXPECT_EQ(vo[2].vertex, 2);
  EXPECT_EQ(fo[0].layer, 3);
  EXPECT_EQ(fo[0].face, 0);
}

TEST(Mesh, ArraysRoundTrip) {
  const Mesh m = testing::box(1, 2, 3);
  const Mesh copy = makeMesh(positionsOf(m), trianglesOf(m));
  EXPECT_EQ(positionsOf(copy), positionsOf(m));
  EXPECT_EQ(trianglesOf(copy), trianglesOf(m));
}

TEST(Mesh, ProvenanceSurvivesAddingElements) {
  Mesh m = testing::tetrahedron();
  vcg::tri::Allocator<Mesh>::AddVertices(m, 10);
  vcg::tri::Allocator<Mesh>::AddFaces(m, 10);
  EXPECT_EQ(vertexOrigins(m)[3].vertex, 3);
  EXPECT_EQ(faceOrigins(m)[3].face, 3);
  EXPECT_EQ(vertexOrigins(m)[12].vertex, -1);
}

TEST(Mesh, RejectsIndexOutOfRange) {
  try {
    makeMesh({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, {{0, 1, 7}});
    FAIL() << "expected InvalidInputError";
  } catch (const InvalidInputError& e) {
    EXPECT_NE(std::string(e.what()).find("face 0 refers to vertex 7"), std::string::npos);
  }
  EXPECT_THROW(makeMesh({{0, 0, 0}}, {{0, 0, -1}}), InvalidInputError);
}

// The parts of a MeshBuilder, in any order and on two threads at once,
// build the mesh buildMesh builds; and it keeps working after elements are
// added the usual way (its counts and attributes are vcglib's own).
TEST(Mesh, BuilderPartsOnTwoThreadsBuildTheSameMesh) {
  const Mesh source = testing::box(1, 2, 3);
  const std::vector<Point3> positions = positionsOf(source);
  const std::vector<Triangle> triangles = trianglesOf(source);
  std::vector<VertexOrigin> vo(positions.size());
  std::vector<FaceOrigin> fo(triangles.size());
  for (std::size_t v = 0; v < vo.size(); ++v) vo[v] = {1, int(v), -1, {0, 0, 0}};
  for (std::size_t f = 0; f < fo.size(); ++f) fo[f] = {2, int(f) + 10};
  Mesh serial, parallel;
  buildMesh(serial, positions, triangles, vo, fo);
  {
    MeshBuilder builder(parallel, positions, triangles, vo, fo);
    std::thread other([&] {
      builder.build(MeshBuilder::kFaceOrigins);
      builder.build(MeshBuilder::kVertices);
    });
    builder.build(MeshBuilder::kFaces);
    builder.build(MeshBuilder::kVertexOrigins);
    other.join();
    builder.link();
  }
  for (const Mesh* m : {&serial, &parallel}) {
    EXPECT_EQ(positionsOf(*m), positions);
    EXPECT_EQ(trianglesOf(*m), triangles);
    EXPECT_EQ(m->vn, int(positions.size()));
    EXPECT_EQ(m->fn, int(triangles.size()));
    Mesh& mesh = const_cast<Mesh&>(*m);
    EXPECT_EQ(vertexOrigins(mesh)[5].layer, 1);
    EXPECT_EQ(vertexOrigins(mesh)[5].vertex, 5);
    EXPECT_EQ(faceOrigins(mesh)[3].layer, 2);
    EXPECT_EQ(faceOrigins(mesh)[3].face, 13);
  }
  vcg::tri::Allocator<Mesh>::AddVertices(parallel, 2);
  EXPECT_EQ(parallel.vn, int(positions.size()) + 2);
  EXPECT_EQ(vertexOrigins(parallel)[positions.size() + 1].vertex, -1);
  EXPECT_EQ(vertexOrigins(parallel)[5].vertex, 5);
}

TEST(Mesh, BuilderRefusesMismatchedOriginsAndBadIndices) {
  Mesh m = testing::tetrahedron();
  const std::vector<Point3> p = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  const std::vector<VertexOrigin> vo(3);
  const std::vector<FaceOrigin> fo(1);
  EXPECT_THROW(MeshBuilder(m, p, {{0, 1, 2}}, vo, {}), std::invalid_argument);
  EXPECT_THROW(MeshBuilder(m, p, {{0, 1, 3}}, vo, fo), InvalidInputError);
  EXPECT_EQ(m.fn, 4);  // refused before the mesh was touched
}

TEST(Mesh, NonFiniteCoordinatesAreRejectedByTheCapabilityCheck) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  const Mesh withNan = makeMesh({{0, 0, 0}, {nan, 0, 0}, {0, 1, 0}}, {{0, 1, 2}});
  const Mesh withInf = makeMesh({{0, 0, inf}, {1, 0, 0}, {0, 1, 0}}, {{0, 1, 2}});
  EXPECT_THROW(requireFacesAndFiniteCoordinates(withNan, "x"), InvalidInputError);
  EXPECT_THROW(requireFacesAndFiniteCoordinates(withInf, "x"), InvalidInputError);
}

TEST(Mesh, RequireFacesNamesTheLayer) {
  try {
    requireFacesAndFiniteCoordinates(Mesh(), "layer 'empty'");
    FAIL() << "expected InvalidInputError";
  } catch (const InvalidInputError& e) {
    EXPECT_NE(std::string(e.what()).find("layer 'empty' has no faces"), std::string::npos);
  }
  Mesh m = testing::tetrahedron();
  m.vert[1].P()[2] = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(requireFacesAndFiniteCoordinates(m, "x"), InvalidInputError);
  EXPECT_NO_THROW(requireFacesAndFiniteCoordinates(testing::tetrahedron(), "x"));
}

TEST(Mesh, CoordinateSpanCoversEveryFloatAndRefusesWider) {
  // Every float mesh: a subnormal float beside FLT_MAX (277 binades).
  const double tiny = std::numeric_limits<float>::denorm_min();
  const double big = std::numeric_limits<float>::max();
  const Mesh floats = makeMesh({{tiny, 0, 0}, {big, 0, 0}, {0, big, 0}}, {{0, 1, 2}});
  EXPECT_NEAR(magnitudesOf(positionsOf(floats), trianglesOf(floats)).binades(), 277, 1);
  EXPECT_NO_THROW(requireFacesAndFiniteCoordinates(floats, "x"));
  // Double coordinates from 1e-200 to 1e100 (997 binades): refused, naming
  // the span and the coordinates to set to zero.
  const Mesh wide = makeMesh({{1e-200, 0, 0}, {1e100, 0, 0}, {0, 1, 0}}, {{0, 1, 2}});
  try {
    requireFacesAndFiniteCoordinates(wide, "layer 'part'");
    FAIL() << "expected InvalidInputError";
  } catch (const InvalidInputError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("layer 'part': its coordinates span 997 binades"), std::string::npos) << m;
    EXPECT_NE(m.find("set them to zero"), std::string::npos) << m;
  }
  // Zeros and unused vertices do not count.
  const Mesh unused = makeMesh({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1e-300, 0, 0}}, {{0, 1, 2}});
  EXPECT_EQ(magnitudesOf(positionsOf(unused), trianglesOf(unused)).binades(), 0);
  EXPECT_NO_THROW(requireFacesAndFiniteCoordinates(unused, "x"));
}

TEST(Mesh, WeldCoincidentVerticesClosesASeam) {
  // A box whose top four faces use their own copies of the top corners.
  Mesh b = testing::box();
  std::vector<Point3> p = positionsOf(b);
  std::vector<Triangle> t = trianglesOf(b);
  for (int v = 4; v < 8; ++v) p.push_back(p[v]);
  t[2] = {8, 9, 10};
  t[3] = {9, 11, 10};
  p.push_back(p[0]);  // an unused duplicate goes too
  Mesh m = makeMesh(p, t);
  faceOrigins(m)[3].face = 77;  // provenance travels with the face
  std::size_t removed = 99;
  EXPECT_EQ(weldCoincidentVertices(m, &removed), 5u);
  EXPECT_EQ(removed, 0u);
  EXPECT_EQ(m.vn, 8);
  EXPECT_EQ(m.fn, 12);
  EXPECT_EQ(faceOrigins(m)[3].face, 77);
  std::size_t again = 0;
  EXPECT_EQ(weldCoincidentVertices(m, &again), 0u);
}

TEST(Mesh, WeldRemovesFacesThatCollapse) {
  Mesh m = makeMesh({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 0, 0}}, {{0, 1, 2}, {0, 1, 3}});
  std::size_t removed = 0;
  EXPECT_EQ(weldCoincidentVertices(m, &removed), 1u);
  EXPECT_EQ(removed, 1u);
  EXPECT_EQ(m.fn, 1);
}

TEST(Mesh, WeldRemovesFacesWithARepeatedCornerEvenWithoutMerging) {
  // Nothing to merge, but a face naming one vertex twice: it goes, as in
  // weldCoincident (the count reported was once not what the mesh held).
  Mesh m = makeMesh({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, {{0, 1, 2}, {0, 0, 1}});
  std::size_t removed = 0;
  EXPECT_EQ(weldCoincidentVertices(m, &removed), 0u);
  EXPECT_EQ(removed, 1u);
  EXPECT_EQ(m.fn, 1);
  EXPECT_EQ(
      weldCoincident(arraysOf(makeMesh({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, {{0, 1, 2}, {0, 0, 1}})))
          .mesh.triangles.size(),
      std::size_t(m.fn));
}

// Rounding coordinates to float and back must really round (GCC 12's SLP
// vectorizer dropped such round trips; the build disables it).
TEST(Mesh, RoundingToFloatRoundsEveryCoordinate) {
  Mesh m = makeMesh(
      {{-0.042701494442573054, 0.16919859668216869, 0.0017091735946980593}, {1, 0, 0}, {0, 1, 0}},
      {{0, 1, 2}});
  for (Vertex& v : m.vert)
    for (int k = 0; k < 3; ++k) v.P()[k] = double(float(v.P()[k]));
  for (int k = 0; k < 3; ++k) EXPECT_EQ(m.vert[0].cP()[k], double(float(m.vert[0].cP()[k])));
  EXPECT_EQ(m.vert[0].cP()[0], -0.042701493948698044);
}

TEST(Mesh, SmallestAngleIsOppositeTheShortestSide) {
  std::srand(7);
  auto random = [] { return std::rand() / double(RAND_MAX) * 2 - 1; };
  auto angle = [](const Point3& p, const Point3& q, const Point3& r) {
    const Point3 u = q - p, v = r - p;
    return std::atan2((u ^ v).Norm(), u * v);
  };
  for (int i = 0; i < 1000; ++i) {
    const Point3 a(random(), random(), random()), b(random(), random(), random()),
        c(random(), random(), random());
    const double expected = std::min({angle(a, b, c), angle(b, c, a), angle(c, a, b)});
    EXPECT_NEAR(smallestAngle(a, b, c), expected, 1e-12);
  }
  EXPECT_NEAR(smallestAngle({0, 0, 0}, {1, 0, 0}, {0, 1, 0}), M_PI / 4, 1e-15);
  EXPECT_EQ(smallestAngle({0, 0, 0}, {1, 0, 0}, {2, 0, 0}), 0);  // collinear
}

}  // namespace
}  // namespace meshmend

// The MeshLab bridge: CMeshO <-> core mesh, and attributes carried through
// provenance. Runs without a display (no GL is touched).
#include "plugins/bridge/mesh_bridge.h"

#include <gtest/gtest.h>
#include <QCoreApplication>

#include "common/base/errors.h"
#include "plugins/bridge/filter_support.h"

namespace meshmend::bridge {
namespace {

// A coloured, textured quad (two triangles) with every optional attribute a
// user's mesh may carry.
MeshModel* texturedQuad(MeshDocument& document) {
  MeshModel* m = document.addNewMesh("", "quad");
  m->updateDataMask(MeshModel::MM_VERTCOLOR | MeshModel::MM_VERTQUALITY |
                    MeshModel::MM_VERTTEXCOORD | MeshModel::MM_FACECOLOR |
                    MeshModel::MM_FACEQUALITY | MeshModel::MM_WEDGTEXCOORD);
  CMeshO& cm = m->cm;
  auto vi = vcg::tri::Allocator<CMeshO>::AddVertices(cm, 4);
  const float xy[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  for (int i = 0; i < 4; ++i, ++vi) {
    vi->P() = Point3m(xy[i][0], xy[i][1], 0.25f);
    vi->N() = Point3m(0, 0, 1);
    vi->C() = vcg::Color4b(60 * i, 255 - 60 * i, 10, 255);
    vi->Q() = float(i) * 1.5f;
    vi->T().U() = xy[i][0];
    vi->T().V() = xy[i][1];
    vi->T().N() = 0;
  }
  auto fi = vcg::tri::Allocator<CMeshO>::AddFaces(cm, 2);
  const int corners[2][3] = {{0, 1, 2}, {0, 2, 3}};
  for (int f = 0; f < 2; ++f, ++fi) {
    for (int k = 0; k < 3; ++k) {
      fi->V(k) = &cm.vert[corners[f][k]];
      fi->WT(k).U() = xy[corners[f][k]][0] * 0.5f;
      fi->WT(k).V() = xy[corners[f][k]][1] * 0.5f;
      fi->WT(k).N() = short(f);  // each face on its own texture
    }
    fi->C() = f == 0 ? vcg::Color4b::Red : vcg::Color4b::Blue;
    fi->Q() = 10.f + f;
  }
  cm.face[1].SetS();
  cm.vert[2].SetS();
  cm.textures = {"a.png", "b.png"};
  return m;
}

TEST(Bridge, RoundTripKeepsEveryAttribute) {
  MeshDocument document;
  MeshModel* in = texturedQuad(document);
  const LayerAttributes attributes = snapshot(*in);
  const Mesh core = toCore(in->cm);
  ASSERT_EQ(core.vn, 4);
  ASSERT_EQ(core.fn, 2);

  MeshModel* out = document.addNewMesh("", "out");
  writeMesh(core, {attributes}, *out);
  ASSERT_EQ(out->cm.vn, 4);
  ASSERT_EQ(out->cm.fn, 2);
  for (int mask : {MeshModel::MM_VERTCOLOR, MeshModel::MM_VERTQUALITY, MeshModel::MM_VERTTEXCOORD,
                   MeshModel::MM_FACECOLOR, MeshModel::MM_FACEQUALITY, MeshModel::MM_WEDGTEXCOORD})
    EXPECT_TRUE(out->hasDataMask(mask)) << mask;
  for (int i = 0; i < 4; ++i) {
    const CVertexO &a = in->cm.vert[i], &b = out->cm.vert[i];
    EXPECT_EQ(a.cP(), b.cP());
    EXPECT_EQ(a.cN(), b.cN());
    EXPECT_EQ(a.cC(), b.cC());
    EXPECT_EQ(a.cQ(), b.cQ());
    EXPECT_EQ(a.cT().U(), b.cT().U());
    EXPECT_EQ(a.cT().V(), b.cT().V());
    EXPECT_EQ(a.IsS(), b.IsS());
  }
  for (int f = 0; f < 2; ++f) {
    const CFaceO &a = in->cm.face[f], &b = out->cm.face[f];
    EXPECT_EQ(a.cC(), b.cC());
    EXPECT_EQ(a.cQ(), b.cQ());
    EXPECT_EQ(a.IsS(), b.IsS());
    for (int k = 0; k < 3; ++k) {
      EXPECT_EQ(vcg::tri::Index(in->cm, a.cV(k)), vcg::tri::Index(out->cm, b.cV(k)));
      EXPECT_EQ(a.cWT(k).U(), b.cWT(k).U());
      EXPECT_EQ(a.cWT(k).V(), b.cWT(k).V());
      EXPECT_EQ(a.cWT(k).N(), b.cWT(k).N());
    }
  }
  EXPECT_EQ(out->cm.textures, in->cm.textures);
}

TEST(Bridge, InPlaceWriteUsesTheSnapshot) {
  MeshDocument document;
  MeshModel* m = texturedQuad(document);
  const LayerAttributes attributes = snapshot(*m);
  const Mesh core = toCore(m->cm);
  writeMesh(core, {attributes}, *m);  // overwrite the input layer itself
  EXPECT_EQ(m->cm.fn, 2);
  EXPECT_EQ(m->cm.face[0].cC(), vcg::Color4b(vcg::Color4b::Red));
  EXPECT_EQ(m->cm.vert[3].cQ(), 4.5f);
}

TEST(Bridge, NewVertexInterpolatesAtItsBarycentricCoordinates) {
  MeshDocument document;
  MeshModel* in = texturedQuad(document);
  const LayerAttributes attributes = snapshot(*in);
  Mesh core = toCore(in->cm);
  // Split face 0 (corners 0, 1, 2) at its centroid, as a core operation would.
  const Point3 centroid = (core.vert[0].cP() + core.vert[1].cP() + core.vert[2].cP()) / 3.0;
  std::vector<Point3> positions = positionsOf(core);
  positions.push_back(centroid);
  Mesh split = makeMesh(positions, {{0, 1, 4}, {1, 2, 4}, {2, 0, 4}, {0, 2, 3}});
  VertexOriginHandle vo = vertexOrigins(split);
  FaceOriginHandle fo = faceOrigins(split);
  vo[4] = VertexOrigin{0, -1, 0, Point3(1.0 / 3, 1.0 / 3, 1.0 / 3)};
  for (int f = 0; f < 3; ++f) fo[f] = FaceOrigin{0, 0};
  fo[3] = FaceOrigin{0, 1};

  MeshModel* out = document.addNewMesh("", "split");
  writeMesh(split, {attributes}, *out);
  const CVertexO& v = out->cm.vert[4];
  EXPECT_NEAR(v.cQ(), (0 + 1.5 + 3.0) / 3, 1e-6);
  EXPECT_EQ(v.cC()[0], (unsigned char)std::lround((0 + 60 + 120) / 3.0));
  EXPECT_NEAR(v.cT().U(), 2.0 / 3, 1e-6);
  // Wedge texture coordinates of the new corner come from face 0's wedges.
  EXPECT_NEAR(out->cm.face[0].cWT(2).U(), (0 + 0.5 + 0.5) / 3, 1e-6);
  EXPECT_NEAR(out->cm.face[0].cWT(2).V(), (0 + 0 + 0.5) / 3, 1e-6);
  EXPECT_EQ(out->cm.face[1].cC(), vcg::Color4b(vcg::Color4b::Red));  // colour of the birth face
  EXPECT_EQ(out->cm.face[3].cC(), vcg::Color4b(vcg::Color4b::Blue));
}

TEST(Bridge, TwoLayersKeepTheirTextures) {
  MeshDocument document;
  MeshModel* a = texturedQuad(document);
  MeshModel* b = texturedQuad(document);
  std::vector<LayerAttributes> inputs{snapshot(*a), snapshot(*b)};
  Mesh ca = toCore(a->cm, {0, false});
  Mesh cb = toCore(b->cm, {1, false});
  vcg::tri::Append<Mesh, Mesh>::Mesh(ca, cb);  // origins travel with the elements
  MeshModel* out = document.addNewMesh("", "both");
  writeMesh(ca, inputs, *out);
  ASSERT_EQ(out->cm.fn, 4);
  EXPECT_EQ(out->cm.textures.size(), 4u);
  EXPECT_EQ(out->cm.face[3].cWT(0).N(), 1 + 2);  // layer 1's texture 1, after layer 0's two
}

TEST(Bridge, ToCoreSkipsDeletedElementsAndKeepsTheirSlots) {
  MeshDocument document;
  MeshModel* m = texturedQuad(document);
  vcg::tri::Allocator<CMeshO>::DeleteFace(m->cm, m->cm.face[0]);
  vcg::tri::Allocator<CMeshO>::DeleteVertex(m->cm, m->cm.vert[1]);
  Mesh core = toCore(m->cm);
  ASSERT_EQ(core.vn, 3);
  ASSERT_EQ(core.fn, 1);
  EXPECT_EQ(faceOrigins(core)[0].face, 1);
  EXPECT_EQ(vertexOrigins(core)[1].vertex, 2);
}

TEST(Bridge, ToCoreRefusesFacesPointingOutsideTheVertexArray) {
  MeshDocument document;
  MeshModel* m = texturedQuad(document);
  CVertexO* outside = &m->cm.vert.back() + 5;  // what a corrupt OFF index leaves behind
  m->cm.face[1].V(2) = outside;
  EXPECT_THROW(toCore(m->cm), InvalidInputError);
  m->cm.face[1].V(2) = &m->cm.vert[3];
  vcg::tri::Allocator<CMeshO>::DeleteVertex(m->cm, m->cm.vert[3]);
  EXPECT_THROW(toCore(m->cm), InvalidInputError);
}

TEST(Bridge, ToCoreAppliesTheLayerMatrixWhenAsked) {
  MeshDocument document;
  MeshModel* m = texturedQuad(document);
  m->cm.Tr.SetTranslate(10, 0, 0);
  EXPECT_EQ(toCore(m->cm).vert[1].cP()[0], 1.0);
  EXPECT_EQ(toCore(m->cm, {0, true}).vert[1].cP()[0], 11.0);
}

TEST(Bridge, GuardedTurnsErrorsIntoMessages) {
  QString message;
  std::string logged;
  auto log = [&](const std::string& m) { logged = m; };
  EXPECT_FALSE(guarded(
      message, [] { throw InvalidInputError("layer 'x' has no faces"); }, log));
  EXPECT_EQ(message, "layer 'x' has no faces");
  EXPECT_EQ(logged, "MeshMend error: layer 'x' has no faces");
  logged.clear();
  EXPECT_TRUE(guarded(
      message, [] {}, log));
  EXPECT_TRUE(logged.empty());
  EXPECT_FALSE(guarded(
      message, [] { throw std::logic_error("boom"); }, log));
  EXPECT_TRUE(message.contains("internal error: boom"));
}

}  // namespace
}  // namespace meshmend::bridge

int main(int argc, char** argv) {
  QCoreApplication app(argc, argv);
  ::testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}

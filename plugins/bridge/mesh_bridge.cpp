#include "plugins/bridge/mesh_bridge.h"

#include "common/base/errors.h"
#include "common/base/huge_pages.h"

#include <algorithm>
#include <cmath>
#include <string>

#include <vcg/complex/algorithms/update/bounding.h>
#include <vcg/complex/algorithms/update/normal.h>

namespace meshmend::bridge {

Mesh toCore(const CMeshO& cm, const ToCoreOptions& options) {
  Mesh mesh;
  toCore(cm, mesh, options);
  return mesh;
}

void toCore(const CMeshO& cm, Mesh& mesh, const ToCoreOptions& options) {
  std::vector<Point3> positions;
  std::vector<int> vertexSlot;  // core vertex -> index in cm.vert
  std::vector<int> coreIndex;
  assignInHugePages(coreIndex, cm.vert.size(), -1);
  reserveInHugePages(positions, std::size_t(cm.vn));
  reserveInHugePages(vertexSlot, std::size_t(cm.vn));
  const vcg::Matrix44d tr = vcg::Matrix44d::Construct(cm.Tr);
  for (std::size_t i = 0; i < cm.vert.size(); ++i) {
    if (cm.vert[i].IsD()) continue;
    Point3 p = Point3::Construct(cm.vert[i].cP());
    if (options.apply_transform) p = tr * p;
    coreIndex[i] = int(positions.size());
    positions.push_back(p);
    vertexSlot.push_back(int(i));
  }
  std::vector<Triangle> triangles;
  std::vector<int> faceSlot;
  reserveInHugePages(triangles, std::size_t(cm.fn));
  reserveInHugePages(faceSlot, std::size_t(cm.fn));
  for (std::size_t f = 0; f < cm.face.size(); ++f) {
    const CFaceO& face = cm.face[f];
    if (face.IsD()) continue;
    Triangle t;
    for (int k = 0; k < 3; ++k) {
      // A corrupt file can leave pointers outside the vertex array (MeshLab's
      // OFF importer does not check face indices): refuse, do not read them.
      const CVertexO* v = face.cV(k);
      const bool inside = !cm.vert.empty() && v >= &cm.vert.front() && v <= &cm.vert.back();
      if (!inside || v->IsD())
        throw InvalidInputError("face " + std::to_string(f) + " refers to a vertex that " +
                                (inside ? "was deleted" : "does not exist") +
                                ": the mesh is corrupt (check the file's face indices)");
      t[k] = coreIndex[vcg::tri::Index(cm, v)];
    }
    triangles.push_back(t);
    faceSlot.push_back(int(f));
  }
  buildMesh(mesh, positions, triangles, options.layer);
  VertexOriginHandle vo = vertexOrigins(mesh);
  FaceOriginHandle fo = faceOrigins(mesh);
  for (std::size_t i = 0; i < vertexSlot.size(); ++i) vo[i].vertex = vertexSlot[i];
  for (std::size_t f = 0; f < faceSlot.size(); ++f) fo[f].face = faceSlot[f];
}

LayerAttributes snapshot(const MeshModel& model) {
  const CMeshO& cm = model.cm;
  LayerAttributes a;
  a.vertex_color = model.hasDataMask(MeshModel::MM_VERTCOLOR);
  a.vertex_quality = model.hasDataMask(MeshModel::MM_VERTQUALITY);
  a.vertex_texcoord = model.hasDataMask(MeshModel::MM_VERTTEXCOORD);
  a.face_color = model.hasDataMask(MeshModel::MM_FACECOLOR);
  a.face_quality = model.hasDataMask(MeshModel::MM_FACEQUALITY);
  a.wedge_texcoord = model.hasDataMask(MeshModel::MM_WEDGTEXCOORD);
  const std::size_t nv = cm.vert.size(), nf = cm.face.size();
  resizeInHugePages(a.positions, nv);
  resizeInHugePages(a.vertex_normals, nv);
  a.vertex_selected.resize(nv);
  if (a.vertex_color) resizeInHugePages(a.vertex_colors, nv);
  if (a.vertex_quality) resizeInHugePages(a.vertex_qualities, nv);
  if (a.vertex_texcoord) resizeInHugePages(a.vertex_texcoords, nv);
  for (std::size_t i = 0; i < nv; ++i) {
    const CVertexO& v = cm.vert[i];
    a.positions[i] = vcg::Point3d::Construct(v.cP());
    a.vertex_normals[i] = v.cN();
    a.vertex_selected[i] = !v.IsD() && v.IsS();
    if (a.vertex_color) a.vertex_colors[i] = v.cC();
    if (a.vertex_quality) a.vertex_qualities[i] = v.cQ();
    if (a.vertex_texcoord) a.vertex_texcoords[i] = v.cT();
  }
  resizeInHugePages(a.faces, nf);
  a.face_selected.resize(nf);
  if (a.face_color) resizeInHugePages(a.face_colors, nf);
  if (a.face_quality) resizeInHugePages(a.face_qualities, nf);
  if (a.wedge_texcoord) resizeInHugePages(a.wedge_texcoords, nf);
  for (std::size_t f = 0; f < nf; ++f) {
    const CFaceO& face = cm.face[f];
    if (face.IsD()) continue;
    for (int k = 0; k < 3; ++k) a.faces[f][k] = int(vcg::tri::Index(cm, face.cV(k)));
    a.face_selected[f] = face.IsS();
    if (a.face_color) a.face_colors[f] = face.cC();
    if (a.face_quality) a.face_qualities[f] = face.cQ();
    if (a.wedge_texcoord)
      for (int k = 0; k < 3; ++k) a.wedge_texcoords[f][k] = face.cWT(k);
  }
  a.textures = cm.textures;
  return a;
}

namespace {

// Barycentric coordinates of p projected onto the plane of triangle (a, b, c);
// a degenerate triangle gives the nearest corner weight 1.
vcg::Point3d barycentricOf(const vcg::Point3d& p, const vcg::Point3d& a, const vcg::Point3d& b,
                           const vcg::Point3d& c) {
  const vcg::Point3d e0 = b - a, e1 = c - a, d = p - a;
  const double d00 = e0 * e0, d01 = e0 * e1, d11 = e1 * e1, d20 = d * e0, d21 = d * e1;
  const double denom = d00 * d11 - d01 * d01;
  if (!(std::fabs(denom) > 0)) {
    const double da = (p - a).SquaredNorm(), db = (p - b).SquaredNorm(), dc = (p - c).SquaredNorm();
    if (da <= db && da <= dc) return {1, 0, 0};
    return db <= dc ? vcg::Point3d(0, 1, 0) : vcg::Point3d(0, 0, 1);
  }
  const double v = (d11 * d20 - d01 * d21) / denom;
  const double w = (d00 * d21 - d01 * d20) / denom;
  return {1 - v - w, v, w};
}

vcg::Color4b mix(const vcg::Color4b c[3], const vcg::Point3d& w) {
  vcg::Color4b out;
  for (int k = 0; k < 4; ++k) {
    const double v = w[0] * c[0][k] + w[1] * c[1][k] + w[2] * c[2][k];
    out[k] = (unsigned char)(std::lround(std::min(255.0, std::max(0.0, v))));
  }
  return out;
}

// What an output face is to the inputs: a copy of its origin face (the same
// three input corners), a piece cut from it, or new (no origin face).
unsigned char faceChange(const Mesh& core, const Face& face, VertexOriginHandle& vo,
                         const FaceOrigin& o, const LayerAttributes* in) {
  if (!in || o.face < 0 || o.face >= int(in->faces.size())) return kFaceNew;
  const std::array<int, 3>& corners = in->faces[o.face];
  for (int k = 0; k < 3; ++k) {
    const VertexOrigin& v = vo[vcg::tri::Index(core, face.cV(k))];
    if (v.layer != o.layer || std::find(corners.begin(), corners.end(), v.vertex) == corners.end())
      return kFaceCut;
  }
  return kFaceKept;
}

}  // namespace

void writeMesh(const Mesh& core, const std::vector<LayerAttributes>& inputs, MeshModel& out) {
  Mesh& mesh = const_cast<Mesh&>(core);  // vcglib attribute lookup needs a mutable mesh
  VertexOriginHandle vo = vertexOrigins(mesh);
  FaceOriginHandle fo = faceOrigins(mesh);

  bool vertexColor = false, vertexQuality = false, vertexTex = false;
  bool faceColor = false, faceQuality = false, wedgeTex = false;
  std::vector<int> textureOffset;
  std::vector<std::string> textures;
  for (const LayerAttributes& in : inputs) {
    vertexColor |= in.vertex_color;
    vertexQuality |= in.vertex_quality;
    vertexTex |= in.vertex_texcoord;
    faceColor |= in.face_color;
    faceQuality |= in.face_quality;
    wedgeTex |= in.wedge_texcoord;
    textureOffset.push_back(int(textures.size()));
    textures.insert(textures.end(), in.textures.begin(), in.textures.end());
  }

  CMeshO& cm = out.cm;
  const Matrix44m keepTr = cm.Tr;
  cm.Clear();
  cm.Tr = keepTr;
  int mask = 0;
  if (vertexColor) mask |= MeshModel::MM_VERTCOLOR;
  if (vertexQuality) mask |= MeshModel::MM_VERTQUALITY;
  if (vertexTex) mask |= MeshModel::MM_VERTTEXCOORD;
  if (faceColor) mask |= MeshModel::MM_FACECOLOR;
  if (faceQuality) mask |= MeshModel::MM_FACEQUALITY;
  if (wedgeTex) mask |= MeshModel::MM_WEDGTEXCOORD;
  if (mask) out.updateDataMask(mask);
  cm.textures = textures;

  const LayerAttributes* none = nullptr;
  auto layerOf = [&](int layer) {
    return layer >= 0 && layer < int(inputs.size()) ? &inputs[layer] : none;
  };

  // The host's arrays too: its elements are large (a face is some hundred
  // bytes), and a million of them new memory. Reserved on the empty mesh,
  // where adding them moves nothing; the optional components' arrays
  // (vector_ocf's own) are sized as the elements are added.
  reserveInHugePages(cm.vert, core.vert.size());
  reserveInHugePages(cm.face, core.face.size());
  auto vi = vcg::tri::Allocator<CMeshO>::AddVertices(cm, core.vert.size());
  for (std::size_t i = 0; i < core.vert.size(); ++i, ++vi) {
    vi->P() = HostPoint::Construct(core.vert[i].cP());
    const VertexOrigin& o = vo[i];
    const LayerAttributes* in = layerOf(o.layer);
    if (!in) continue;
    if (o.vertex >= 0 && o.vertex < int(in->positions.size())) {
      const int v = o.vertex;
      vi->N() = in->vertex_normals[v];
      if (in->vertex_selected[v]) vi->SetS();
      if (in->vertex_color) vi->C() = in->vertex_colors[v];
      if (in->vertex_quality) vi->Q() = in->vertex_qualities[v];
      if (in->vertex_texcoord) {
        vi->T() = in->vertex_texcoords[v];
        vi->T().N() = short(vi->T().N() + textureOffset[o.layer]);
      }
    } else if (o.face >= 0 && o.face < int(in->faces.size())) {
      const std::array<int, 3>& c = in->faces[o.face];
      const vcg::Point3d& w = o.barycentric;
      HostPoint n(0, 0, 0);
      for (int k = 0; k < 3; ++k) n += in->vertex_normals[c[k]] * HostScalar(w[k]);
      vi->N() = n.Normalize();
      if (in->vertex_color) {
        const vcg::Color4b cols[3] = {in->vertex_colors[c[0]], in->vertex_colors[c[1]],
                                      in->vertex_colors[c[2]]};
        vi->C() = mix(cols, w);
      }
      if (in->vertex_quality) {
        double q = 0;
        for (int k = 0; k < 3; ++k) q += w[k] * in->vertex_qualities[c[k]];
        vi->Q() = HostScalar(q);
      }
      if (in->vertex_texcoord) {
        vcg::TexCoord2f t;
        t.U() = t.V() = 0;
        t.N() = in->vertex_texcoords[c[0]].N();
        for (int k = 0; k < 3; ++k) {
          t.U() += float(w[k]) * in->vertex_texcoords[c[k]].U();
          t.V() += float(w[k]) * in->vertex_texcoords[c[k]].V();
        }
        t.N() = short(t.N() + textureOffset[o.layer]);
        vi->T() = t;
      }
    }
  }

  auto fi = vcg::tri::Allocator<CMeshO>::AddFaces(cm, core.face.size());
  auto change =
      vcg::tri::Allocator<CMeshO>::GetPerFaceAttribute<unsigned char>(cm, kFaceChangeAttribute);
  for (std::size_t f = 0; f < core.face.size(); ++f, ++fi) {
    const Face& face = core.face[f];
    for (int k = 0; k < 3; ++k) fi->V(k) = &cm.vert[vcg::tri::Index(core, face.cV(k))];
    const FaceOrigin& o = fo[f];
    const LayerAttributes* in = layerOf(o.layer);
    change[f] = faceChange(core, face, vo, o, in);
    if (!in || o.face < 0 || o.face >= int(in->faces.size())) continue;
    if (in->face_selected[o.face]) fi->SetS();
    if (in->face_color) fi->C() = in->face_colors[o.face];
    if (in->face_quality) fi->Q() = in->face_qualities[o.face];
    if (in->wedge_texcoord) {
      // Each corner takes the birth face's wedge coordinates interpolated at
      // its position: exact for untouched faces, continuous for cut ones.
      const std::array<int, 3>& c = in->faces[o.face];
      const std::array<vcg::TexCoord2f, 3>& wt = in->wedge_texcoords[o.face];
      for (int k = 0; k < 3; ++k) {
        const int v = int(vcg::tri::Index(core, face.cV(k)));
        const VertexOrigin& vorig = vo[v];
        int corner = -1;
        if (vorig.layer == o.layer)
          for (int j = 0; j < 3; ++j)
            if (c[j] == vorig.vertex) corner = j;
        vcg::TexCoord2f t;
        if (corner >= 0) {
          t = wt[corner];
        } else {
          const vcg::Point3d w = barycentricOf(face.cV(k)->cP(), in->positions[c[0]],
                                               in->positions[c[1]], in->positions[c[2]]);
          t.U() = float(w[0] * wt[0].U() + w[1] * wt[1].U() + w[2] * wt[2].U());
          t.V() = float(w[0] * wt[0].V() + w[1] * wt[1].V() + w[2] * wt[2].V());
          t.N() = wt[0].N();
        }
        t.N() = short(t.N() + textureOffset[o.layer]);
        fi->WT(k) = t;
      }
    }
  }
  // Face normals follow the new geometry; vertex normals stay as carried
  // (a user's imported normals survive untouched regions).
  vcg::tri::UpdateBounding<CMeshO>::Box(cm);
  vcg::tri::UpdateNormal<CMeshO>::PerFaceNormalized(cm);
}

}  // namespace meshmend::bridge

#include "io_mend_obj.h"

#include <cmath>
#include <cstdio>

#include <vcg/complex/algorithms/update/bounding.h>
#include <wrap/io_trimesh/io_mask.h>
#include <QFileInfo>

#include "common/io/obj_reader.h"
#include "plugins/bridge/filter_support.h"

using namespace meshmend;
using namespace meshmend::bridge;
namespace io = vcg::tri::io;

QList<MeshIOInterface::Format> ObjImportPlugin::importFormats() const {
  return {Format("Alias Wavefront Object (MeshMend importer)", "OBJ")};
}

namespace {

vcg::Color4b toColor(const std::array<float, 3>& rgb, float alpha = 1) {
  auto byte = [](float v) {
    return (unsigned char)(std::lround(std::min(1.0f, std::max(0.0f, v)) * 255));
  };
  return vcg::Color4b(byte(rgb[0]), byte(rgb[1]), byte(rgb[2]), byte(alpha));
}

}  // namespace

bool ObjImportPlugin::open(const QString&, const QString& fileName, MeshModel& m, int& mask,
                           const RichParameterList&, vcg::CallBackPos* cb, QWidget*) {
  // meshlabserver neither shows an importer's error message nor gives it a
  // log: errors also go to standard error.
  auto toStderr = [](const std::string& m) { std::fprintf(stderr, "%s\n", m.c_str()); };
  return guarded(
      errorMessage,
      [&] {
        if (cb) cb(0, "Reading OBJ");
        const ObjData obj = readObj(toStd(fileName));

        bool wedgeTex = false, wedgeNormals = false;
        for (const auto& polygon : obj.polygons)
          for (const ObjCorner& c : polygon) {
            wedgeTex |= c.texcoord >= 0;
            wedgeNormals |= c.normal >= 0;
          }
        bool anyMaterial = false, anyTexture = false;
        for (int material : obj.polygon_material) anyMaterial |= material >= 0;
        std::vector<int> textureOf(obj.materials.size(), -1);  // material -> cm.textures index
        std::vector<std::string> textures;
        for (std::size_t i = 0; i < obj.materials.size(); ++i)
          if (!obj.materials[i].diffuse_texture.empty()) {
            textureOf[i] = int(textures.size());
            textures.push_back(obj.materials[i].diffuse_texture);
            anyTexture = true;
          }

        mask = io::Mask::IOM_VERTCOORD | io::Mask::IOM_FACEINDEX;
        if (wedgeTex) mask |= io::Mask::IOM_WEDGTEXCOORD;
        if (wedgeNormals) mask |= io::Mask::IOM_VERTNORMAL;
        if (anyMaterial) mask |= io::Mask::IOM_FACECOLOR;
        if (!obj.vertex_colors.empty()) mask |= io::Mask::IOM_VERTCOLOR;
        m.Enable(mask);

        CMeshO& cm = m.cm;
        cm.Clear();
        auto vi = vcg::tri::Allocator<CMeshO>::AddVertices(cm, obj.positions.size());
        for (std::size_t i = 0; i < obj.positions.size(); ++i, ++vi) {
          vi->P() = vcg::Point3f::Construct(obj.positions[i]);
          if (!obj.vertex_colors.empty()) vi->C() = toColor(obj.vertex_colors[i]);
        }
        std::size_t triangles = 0;
        for (const auto& polygon : obj.polygons) triangles += polygon.size() - 2;
        auto fi = vcg::tri::Allocator<CMeshO>::AddFaces(cm, triangles);
        std::vector<vcg::Point3f> normalSum(obj.positions.size(), vcg::Point3f(0, 0, 0));
        for (std::size_t p = 0; p < obj.polygons.size(); ++p) {
          const auto& polygon = obj.polygons[p];
          const int material = obj.polygon_material[p];
          // Fan triangulation (v0, vi, vi+1); the diagonals are faux edges so that
          // MeshLab still shows the polygon's outline.
          for (std::size_t i = 1; i + 1 < polygon.size(); ++i, ++fi) {
            const ObjCorner* corners[3] = {&polygon[0], &polygon[i], &polygon[i + 1]};
            for (int k = 0; k < 3; ++k) {
              fi->V(k) = &cm.vert[corners[k]->vertex];
              if (wedgeTex) {
                const int t = corners[k]->texcoord;
                fi->WT(k).U() = t >= 0 ? float(obj.texcoords[t][0]) : 0.f;
                fi->WT(k).V() = t >= 0 ? float(obj.texcoords[t][1]) : 0.f;
                fi->WT(k).N() = short(material >= 0 ? textureOf[material] : -1);
              }
              if (corners[k]->normal >= 0)
                normalSum[corners[k]->vertex] +=
                    vcg::Point3f::Construct(obj.normals[corners[k]->normal]);
            }
            if (i > 1) fi->SetF(0);                   // edge (v0, vi) is a diagonal
            if (i + 2 < polygon.size()) fi->SetF(2);  // edge (vi+1, v0) is a diagonal
            if (anyMaterial && material >= 0)
              fi->C() = toColor(obj.materials[material].diffuse, obj.materials[material].opacity);
            else if (anyMaterial)
              fi->C() = vcg::Color4b::White;
          }
        }
        if (wedgeNormals)  // OBJ normals are per corner; MeshLab keeps one per vertex
          for (std::size_t i = 0; i < cm.vert.size(); ++i)
            if (normalSum[i].SquaredNorm() > 0) cm.vert[i].N() = normalSum[i].Normalize();
        if (anyTexture) cm.textures = textures;
        vcg::tri::UpdateBounding<CMeshO>::Box(cm);

        QStringList notes;
        for (const std::string& w : obj.warnings) notes << toQ(w);
        if (!notes
                 .isEmpty())  // MeshLab shows a non-empty message of a successful open as a warning
          errorMessage =
              "While opening '" + QFileInfo(fileName).fileName() + "': " + notes.join("; ");
        if (cb) cb(100, "Reading OBJ");
      },
      toStderr);
}

MESHLAB_PLUGIN_NAME_EXPORTER(ObjImportPlugin)

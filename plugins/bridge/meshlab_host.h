// The MeshLab a plugin is built for, and the few types and document
// operations whose spelling differs between the supported hosts. The build
// chooses the plugin API (plugins/CMakeLists.txt) by which headers the MeshLab
// source provides, and the scalar by MESHMEND_MESHLAB_SCALAR:
//   MESHMEND_MESHLAB_API 2020: MeshLab 2020.09 (Debian bookworm), float, MeshFilterInterface;
//   MESHMEND_MESHLAB_API 2022: MeshLab 2022.02 and 2025.07, float or double, FilterPlugin.
// Everything else in the plugins is written once against what all share.
#pragma once

#include <type_traits>
#include <vector>

#if !defined(MESHMEND_MESHLAB_API)
#error "MESHMEND_MESHLAB_API must be 2020 or 2022 (set by plugins/CMakeLists.txt)"
#elif MESHMEND_MESHLAB_API == 2022
#include <common/ml_document/mesh_document.h>
#include <common/mlexception.h>
#include <common/plugins/interfaces/filter_plugin.h>
#elif MESHMEND_MESHLAB_API == 2020
#include <common/interfaces.h>
#include <common/meshmodel.h>
#else
#error "MESHMEND_MESHLAB_API must be 2020 or 2022"
#endif

namespace meshmend::bridge {

// A distance parameter that the dialog also takes as a percentage of the
// bounding box diagonal ("RichAbsPerc" in scripts on every host); MeshLab
// 2025.07 renamed its class.
#if __has_include(<common/parameters/rich_parameter/rich_percentage.h>)
using RichDistance = RichPercentage;
#else
using RichDistance = RichAbsPerc;
#endif

// MeshLab's own coordinate type: float in 2020.09, double in pymeshlab's build.
using HostScalar = CMeshO::ScalarType;
using HostPoint = CMeshO::CoordType;
// Whether the document stores float: the filters then decide on (and check)
// the coordinates rounded as they will be stored.
inline constexpr bool kHostStoresFloat = std::is_same_v<HostScalar, float>;
// Its name, for the messages and tooltips that say how the result is stored.
inline constexpr const char* kHostPrecision = kHostStoresFloat ? "float" : "double";

// The document's layers, in the layer dialog's order.
inline std::vector<MeshModel*> layersOf(MeshDocument& md) {
  std::vector<MeshModel*> layers;
#if MESHMEND_MESHLAB_API == 2022
  for (MeshModel& m : md.meshIterator()) layers.push_back(&m);
#else
  for (MeshModel* m : md.meshList) layers.push_back(m);
#endif
  return layers;
}

inline void setLayerVisible(MeshModel& layer, bool visible) {
#if MESHMEND_MESHLAB_API == 2022
  layer.setVisible(visible);
#else
  layer.visible = visible;
#endif
}

inline void deleteLayer(MeshDocument& md, MeshModel* layer) {
#if MESHMEND_MESHLAB_API == 2022
  md.delMesh(layer->id());
#else
  md.delMesh(layer);
#endif
}

// A layer parameter ("which layer") defaulting to `layer`.
inline RichMesh layerParameter(const QString& name, MeshModel* layer, MeshDocument& md,
                               const QString& description, const QString& tooltip) {
#if MESHMEND_MESHLAB_API == 2022
  return RichMesh(name, layer ? layer->id() : 0, &md, description, tooltip);
#else
  return RichMesh(name, layer, &md, description, tooltip);
#endif
}

// The layer a layer parameter names; null when the document has no such layer
// (a script may name one it does not have).
inline MeshModel* layerFrom(const RichParameterList& parameters, MeshDocument& md,
                            const QString& name) {
#if MESHMEND_MESHLAB_API == 2022
  return md.getMesh(parameters.getMeshId(name));
#else
  (void)md;
  return parameters.getMesh(name);
#endif
}

}  // namespace meshmend::bridge

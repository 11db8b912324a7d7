// "MeshMend: Prepare Shader View": puts MeshMend's values (clearance, patch
// ids, the faces a filter made) where MeshLab's shaders can read them, for
// the shaders in shaders/ (common/render_channels.h).
#pragma once

#include "plugins/bridge/filter_plugin.h"

class RenderValuesPlugin : public QObject, public meshmend::bridge::FilterAdapter {
  Q_OBJECT
  MESHLAB_PLUGIN_IID_EXPORTER(MESHMEND_FILTER_IID)
  Q_INTERFACES(MESHMEND_FILTER_INTERFACE)

 public:
  enum { PREPARE_SHADER_VIEW };

  RenderValuesPlugin();
  QString pluginName() const override { return "MeshMendRender"; }
  QString filterName(FilterIDType filter) const override;
  QString pythonFilterName(FilterIDType filter) const override;
  QString filterInfo(FilterIDType filter) const override;
  FilterClass filterClass(QAction*) const override { return Texture; }
  Arity arity(QAction*) const override { return SINGLE_MESH; }
  int preconditions(QAction*) const override { return MeshModel::MM_NONE; }
  int postconditions(QAction*) const override { return MeshModel::MM_WEDGTEXCOORD; }
  void initParameters(QAction*, MeshDocument& md, RichParameterList& parameters) override;
  void apply(QAction* filter, MeshDocument& md, const RichParameterList& parameters,
             vcg::CallBackPos* cb) override;
};

// "MeshMend: Prepare Shader View": puts MeshMend's values (clearance, patch
// ids, the faces a filter made) where MeshLab's shaders can read them, for
// the shaders in shaders/ (common/render_channels.h).
#pragma once

#include <common/interfaces.h>

class RenderValuesPlugin : public QObject, public MeshFilterInterface {
  Q_OBJECT
  MESHLAB_PLUGIN_IID_EXPORTER(MESH_FILTER_INTERFACE_IID)
  Q_INTERFACES(MeshFilterInterface)

 public:
  enum { PREPARE_SHADER_VIEW };

  RenderValuesPlugin();
  QString pluginName() const override { return "MeshMendRender"; }
  QString filterName(FilterIDType filter) const override;
  QString filterInfo(FilterIDType filter) const override;
  FilterClass getClass(QAction*) override { return MeshFilterInterface::Texture; }
  FILTER_ARITY filterArity(QAction*) const override { return SINGLE_MESH; }
  int getPreConditions(QAction*) const override { return MeshModel::MM_NONE; }
  int postCondition(QAction*) const override { return MeshModel::MM_WEDGTEXCOORD; }
  void initParameterSet(QAction*, MeshModel& m, RichParameterList& parameters) override;
  bool applyFilter(QAction* filter, MeshDocument& md, const RichParameterList& parameters,
                   vcg::CallBackPos* cb) override;
};

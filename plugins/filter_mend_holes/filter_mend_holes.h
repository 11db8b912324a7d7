// "MeshMend: Fill Holes (Feature Preserving)": patches that follow the shape
// around each hole (common/holes.h), in place.
#pragma once

#include "plugins/bridge/filter_plugin.h"

class HolesPlugin : public QObject, public meshmend::bridge::FilterAdapter {
  Q_OBJECT
  MESHLAB_PLUGIN_IID_EXPORTER(MESHMEND_FILTER_IID)
  Q_INTERFACES(MESHMEND_FILTER_INTERFACE)

 public:
  enum { FILL_HOLES };

  HolesPlugin();
  QString pluginName() const override { return "MeshMendHoles"; }
  QString filterName(FilterIDType filter) const override;
  QString pythonFilterName(FilterIDType filter) const override;
  QString filterInfo(FilterIDType filter) const override;
  FilterClass filterClass(QAction*) const override { return Remeshing; }
  Arity arity(QAction*) const override { return SINGLE_MESH; }
  int preconditions(QAction*) const override { return MeshModel::MM_NONE; }
  int postconditions(QAction*) const override { return MeshModel::MM_ALL; }
  void initParameters(QAction*, MeshDocument& md, RichParameterList& parameters) override;
  void apply(QAction* filter, MeshDocument& md, const RichParameterList& parameters,
             vcg::CallBackPos* cb) override;
};

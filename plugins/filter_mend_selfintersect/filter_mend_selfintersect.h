// "MeshMend: Remove Self-Intersections": the outer surface of a mesh that
// folds through itself (common/selfintersect.h), in place.
#pragma once

#include "plugins/bridge/filter_plugin.h"

class SelfIntersectPlugin : public QObject, public meshmend::bridge::FilterAdapter {
  Q_OBJECT
  MESHLAB_PLUGIN_IID_EXPORTER(MESHMEND_FILTER_IID)
  Q_INTERFACES(MESHMEND_FILTER_INTERFACE)

 public:
  enum { REMOVE_SELF_INTERSECTIONS };

  SelfIntersectPlugin();
  QString pluginName() const override { return "MeshMendSelfIntersect"; }
  QString filterName(FilterIDType filter) const override;
  QString pythonFilterName(FilterIDType filter) const override;
  QString filterInfo(FilterIDType filter) const override;
  FilterClass filterClass(QAction*) const override { return Cleaning; }
  Arity arity(QAction*) const override { return SINGLE_MESH; }
  int preconditions(QAction*) const override { return MeshModel::MM_NONE; }
  int postconditions(QAction*) const override { return MeshModel::MM_ALL; }
  void initParameters(QAction*, MeshDocument& md, RichParameterList& parameters) override;
  void apply(QAction* filter, MeshDocument& md, const RichParameterList& parameters,
             vcg::CallBackPos* cb) override;
};

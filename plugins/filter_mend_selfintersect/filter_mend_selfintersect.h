// "MeshMend: Remove Self-Intersections": the outer surface of a mesh that
// folds through itself (common/selfintersect.h), in place.
#pragma once

#include <common/interfaces.h>

class SelfIntersectPlugin : public QObject, public MeshFilterInterface {
  Q_OBJECT
  MESHLAB_PLUGIN_IID_EXPORTER(MESH_FILTER_INTERFACE_IID)
  Q_INTERFACES(MeshFilterInterface)

 public:
  enum { REMOVE_SELF_INTERSECTIONS };

  SelfIntersectPlugin();
  QString pluginName() const override { return "MeshMendSelfIntersect"; }
  QString filterName(FilterIDType filter) const override;
  QString filterInfo(FilterIDType filter) const override;
  FilterClass getClass(QAction*) override { return MeshFilterInterface::Cleaning; }
  FILTER_ARITY filterArity(QAction*) const override { return SINGLE_MESH; }
  int getPreConditions(QAction*) const override { return MeshModel::MM_NONE; }
  int postCondition(QAction*) const override { return MeshModel::MM_ALL; }
  void initParameterSet(QAction*, MeshModel& m, RichParameterList& parameters) override;
  bool applyFilter(QAction* filter, MeshDocument& md, const RichParameterList& parameters,
                   vcg::CallBackPos* cb) override;
};

// Intersections between and within layers: "MeshMend: Select Intersecting Faces".
#pragma once

#include <common/interfaces.h>

class IntersectPlugin : public QObject, public MeshFilterInterface {
  Q_OBJECT
  MESHLAB_PLUGIN_IID_EXPORTER(MESH_FILTER_INTERFACE_IID)
  Q_INTERFACES(MeshFilterInterface)

 public:
  enum { SELECT_INTERSECTING };

  IntersectPlugin();
  QString pluginName() const override { return "MeshMendIntersect"; }
  QString filterName(FilterIDType filter) const override;
  QString filterInfo(FilterIDType filter) const override;
  FilterClass getClass(QAction*) override { return MeshFilterInterface::Selection; }
  FILTER_ARITY filterArity(QAction*) const override { return VARIABLE; }
  int getPreConditions(QAction*) const override { return MeshModel::MM_NONE; }
  int postCondition(QAction*) const override { return MeshModel::MM_FACEFLAGSELECT; }
  void initParameterSet(QAction*, MeshDocument& md, RichParameterList& parameters) override;
  bool applyFilter(QAction* filter, MeshDocument& md, const RichParameterList& parameters,
                   vcg::CallBackPos* cb) override;
};

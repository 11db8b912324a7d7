// Intersections between and within layers: "MeshMend: Select Intersecting
// Faces" and "MeshMend: Intersect and Split Layers".
#pragma once

#include <common/interfaces.h>

class IntersectPlugin : public QObject, public MeshFilterInterface {
  Q_OBJECT
  MESHLAB_PLUGIN_IID_EXPORTER(MESH_FILTER_INTERFACE_IID)
  Q_INTERFACES(MeshFilterInterface)

 public:
  enum { SELECT_INTERSECTING, INTERSECT_AND_SPLIT };

  IntersectPlugin();
  QString pluginName() const override { return "MeshMendIntersect"; }
  QString filterName(FilterIDType filter) const override;
  QString filterInfo(FilterIDType filter) const override;
  FilterClass getClass(QAction* a) override {
    return ID(a) == SELECT_INTERSECTING ? MeshFilterInterface::Selection
                                        : MeshFilterInterface::Remeshing;
  }
  FILTER_ARITY filterArity(QAction*) const override { return VARIABLE; }
  int getPreConditions(QAction*) const override { return MeshModel::MM_NONE; }
  int postCondition(QAction* a) const override {
    return ID(a) == SELECT_INTERSECTING ? int(MeshModel::MM_FACEFLAGSELECT)
                                        : int(MeshModel::MM_ALL);
  }
  void initParameterSet(QAction*, MeshDocument& md, RichParameterList& parameters) override;
  bool applyFilter(QAction* filter, MeshDocument& md, const RichParameterList& parameters,
                   vcg::CallBackPos* cb) override;

 private:
  void selectIntersecting(MeshDocument& md, const RichParameterList& parameters,
                          vcg::CallBackPos* cb);
  void intersectAndSplit(MeshDocument& md, const RichParameterList& parameters,
                         vcg::CallBackPos* cb);
};
